// Methods (methods/method.hpp): a round plan's bytes, the one-shot designs, the Saltelli design
// and its sensitivity, and the toy two-round method of tests/methods/two_round.hpp, whose rounds
// are planned from records made here with known statistics.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "campaign_fixtures.hpp"
#include "io/scene_toml.hpp"
#include "methods/fixed_design.hpp"
#include "methods/two_round.hpp"

using namespace truss;
using namespace truss::methods;
using campaign::test::small_campaign;

TEST_CASE("a round plan's bytes read back to it; bytes that are not one are refused", "[methods]") {
  const RoundPlan p{3, 1200, 400, std::string("\0state\xff", 7)};
  std::string b;
  p.append_bytes(b);
  CHECK(b.size() == 8 * 3 + 4 + 7);
  CHECK(RoundPlan::from_bytes(b) == p);
  CHECK(p.contains(1200));
  CHECK(p.contains(1599));
  CHECK_FALSE(p.contains(1600));
  CHECK_FALSE(p.contains(1199));
  CHECK_THROWS_AS(RoundPlan::from_bytes(std::string_view(b).substr(0, b.size() - 1)), std::runtime_error);
  CHECK_THROWS_AS(RoundPlan::from_bytes(b + "x"), std::runtime_error);
}

// The journal's digest of a plan: its runs, the state's length and its CRC-32, the bytes as Python
// writes them (struct.pack("<qqqII", 3, 1200, 400, 7, zlib.crc32(b"\0state\xff"))); a state that
// differs in one byte has another digest.
TEST_CASE("a round plan's digest: its bytes, and another state's digest differs", "[methods]") {
  const RoundPlan p{3, 1200, 400, std::string("\0state\xff", 7)};
  const PlanDigest d = PlanDigest::of(p);
  CHECK(d.state_bytes == 7);
  CHECK(d.state_crc32 == 0xf962c69bu);
  const std::string b = d.to_bytes();
  const std::string hex = "0300000000000000b0040000000000009001000000000000070000009bc662f9";
  std::string expected;
  for (std::size_t i = 0; i < hex.size(); i += 2) expected += static_cast<char>(std::stoi(hex.substr(i, 2), nullptr, 16));
  CHECK(b == expected);
  CHECK(PlanDigest::from_bytes(b) == d);
  CHECK(d.contains(1599));
  CHECK_FALSE(d.contains(1600));
  RoundPlan q = p;
  q.state[3] = 'A';
  CHECK_FALSE(PlanDigest::of(q) == d);
  CHECK_THROWS_AS(PlanDigest::from_bytes(std::string_view(b).substr(0, b.size() - 1)), std::runtime_error);
  CHECK_THROWS_AS(PlanDigest::from_bytes(b + "x"), std::runtime_error);
}

TEST_CASE("a one-shot design: one round of n_runs runs, its plan's points, then done", "[methods]") {
  const campaign::CampaignContext ctx(small_campaign("monte_carlo", 24));
  const std::unique_ptr<Method> m = make_method(ctx);
  CHECK(dynamic_cast<FixedDesign*>(m.get()) != nullptr);
  CHECK(dynamic_cast<Saltelli*>(m.get()) == nullptr);
  CHECK(m->observed_outputs().empty());
  const Proposal p0 = m->propose(0, {});
  CHECK(p0.n_runs == 24);
  CHECK(p0.state.empty());
  CHECK(m->propose(1, {}).n_runs == 0);
  // Monte Carlo: u_j = counter_uniform(seed, run, j) (sampling.hpp), whatever the plan says.
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  m->calc_uniforms({0, 0, 24, {}}, 17, u.data());
  for (std::size_t j = 0; j < u.size(); ++j)
    CHECK(u[j] == sampling::counter_uniform(11, 17, static_cast<std::int64_t>(j)));
  const campaign::CampaignContext salt(small_campaign("saltelli", 5 * 8));
  CHECK(dynamic_cast<Saltelli*>(make_method(salt).get()) != nullptr);
}

TEST_CASE("Saltelli design: AB_g takes every dimension of dispersion g from B", "[methods][saltelli]") {
  const campaign::CampaignContext ctx(small_campaign("saltelli", 5 * 8));
  REQUIRE(campaign::saltelli_block_runs(ctx.options) == 5);
  const Saltelli s(ctx);
  const RoundPlan plan{0, 0, 40, {}};
  const campaign::DimensionLayout& L = ctx.dims;
  const auto d = static_cast<std::size_t>(L.total);
  for (std::int64_t block = 0; block < 8; ++block) {
    std::vector<std::vector<double>> u(5, std::vector<double>(d));
    for (int k = 0; k < 5; ++k) s.calc_uniforms(plan, block * 5 + k, u[static_cast<std::size_t>(k)].data());
    for (std::size_t g = 0; g < 3; ++g)
      for (std::size_t j = 0; j < d; ++j) {
        const auto jj = static_cast<int>(j);
        const bool in_g = jj >= L.offset[g] && jj < L.offset[g] + L.count[g];
        CHECK(u[2 + g][j] == (in_g ? u[1][j] : u[0][j]));
        CHECK((u[0][j] > 0.0 && u[0][j] < 1.0));
      }
    CHECK(u[0] != u[1]);
  }
  // Every block has its own A and B.
  std::vector<double> a0(d), a1(d);
  s.calc_uniforms(plan, 0, a0.data());
  s.calc_uniforms(plan, 5, a1.data());
  CHECK(a0 != a1);
  // A run count that is not whole blocks is a campaign error naming ensemble.n_runs.
  try {
    small_campaign("saltelli", 42);
    FAIL("no error");
  } catch (const io::InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("ensemble.n_runs") && Catch::Contains("multiple of 5"));
  }
}

TEST_CASE("Saltelli sensitivity: a block with a failed run or a non-finite output is left out", "[methods][saltelli]") {
  const campaign::CampaignContext ctx(small_campaign("saltelli", 5 * 8));
  const Saltelli s(ctx);
  // Blocks of 5 runs: A, B, AB_1 .. AB_3; the output moves with factor 1 only (f(AB_1) = f(B)).
  std::vector<double> y;
  std::vector<std::int8_t> status(40, 0);
  for (int b = 0; b < 8; ++b) {
    const double a = b, bb = 10.0 - b;
    for (double v : {a, bb, bb, a, a}) y.push_back(v);
  }
  status[7] = 2;   // block 1: a stall
  y[23] = std::numeric_limits<double>::quiet_NaN();  // block 4: no value
  const OutputSensitivity o = s.calc_sensitivity("peak_drive_force_N", status, y);
  CHECK(o.n_blocks == 6);
  CHECK(o.n_blocks_dropped == 2);
  // The estimators (tested in test_sampling) on the six usable blocks, picked here by hand.
  std::vector<double> used;
  for (int b : {0, 2, 3, 5, 6, 7}) used.insert(used.end(), y.begin() + 5 * b, y.begin() + 5 * b + 5);
  const sampling::SobolIndices ref = sampling::calc_sobol_indices(used, 3, 11 ^ 0x53454e53495449ULL, 1000, 0.95);
  CHECK(o.indices.total == ref.total);
  CHECK(o.indices.first_order_lo == ref.first_order_lo);
  // AB_2 = AB_3 = A: factors 2 and 3 change nothing, their indices are exactly 0.
  CHECK(o.indices.total[1] == 0.0);
  CHECK(o.indices.first_order[2] == 0.0);
  const OutputSensitivity none = s.calc_sensitivity("x", std::vector<std::int8_t>(40, 1), y);
  CHECK(none.n_blocks == 0);
  CHECK(std::isnan(none.indices.first_order[0]));
}

namespace {

// Round 0's records as the engine hands them to the method: status and the one observed output.
RoundRecords records(const std::vector<double>& y, const std::vector<std::int8_t>& status) {
  RoundRecords r;
  r.status = status;
  r.outputs = {y};
  return r;
}

}  // namespace

TEST_CASE("two rounds: round 1 adds the runs that bring the mean's interval to its target", "[methods][rounds]") {
  const campaign::CampaignContext ctx(small_campaign("monte_carlo", 100));
  // Round 0: values 1 and 3 alternating over 100 ok runs (mean 2, sample std sqrt(100/99)), plus a
  // failed run and a NaN that do not count: half-width h = 1.96 sqrt(100/99) / 10.
  std::vector<double> y;
  std::vector<std::int8_t> status;
  for (int i = 0; i < 100; ++i) {
    y.push_back(i % 2 ? 3.0 : 1.0);
    status.push_back(0);
  }
  y.push_back(1e6);
  status.push_back(2);
  y.push_back(std::numeric_limits<double>::quiet_NaN());
  status.push_back(0);
  const double h = 1.96 * std::sqrt(100.0 / 99.0) / 10.0;
  {
    test::TwoRound m(ctx, "peak_drive_force_N", 0.05);  // target 0.1: h = 0.197 is too wide
    CHECK(m.observed_outputs() == std::vector<std::string>{"peak_drive_force_N"});
    CHECK(m.propose(0, {}).n_runs == 100);
    const Proposal p1 = m.propose(1, records(y, status));
    CHECK(p1.n_runs == static_cast<std::int64_t>(std::ceil(100.0 * (h / 0.1) * (h / 0.1) - 100.0)));  // 289
    CHECK(p1.n_runs == 289);
    CHECK(p1.state.size() == 8);
    CHECK(m.propose(2, {}).n_runs == 0);
    // Round 1's points depend on round 0's outputs: another mean, other points.
    test::TwoRound other(ctx, "peak_drive_force_N", 0.05);
    std::vector<double> y2 = y;
    y2[0] = 1.5;
    const Proposal q1 = other.propose(1, records(y2, status));
    std::vector<double> u(static_cast<std::size_t>(ctx.dims.total)), v(u.size()), w(u.size());
    m.calc_uniforms({1, 100, p1.n_runs, p1.state}, 150, u.data());
    m.calc_uniforms({1, 100, q1.n_runs, q1.state}, 150, v.data());
    m.calc_uniforms({0, 0, 100, {}}, 150, w.data());
    CHECK(u != v);
    CHECK(u != w);
  }
  {
    test::TwoRound m(ctx, "peak_drive_force_N", 0.2);  // target 0.4 > h: round 0 is enough
    CHECK(m.propose(1, records(y, status)).n_runs == 0);
  }
  {
    test::TwoRound m(ctx, "peak_drive_force_N", 0.001);  // far too wide: capped at 3 n0
    CHECK(m.propose(1, records(y, status)).n_runs == 300);
  }
}

// A configurable method added as one file and one row (tests/methods/two_round.hpp): its option set
// in the campaign file changes its rounds; its bad values are refused with file, line and key.
TEST_CASE("a method's own option: read by its row from the campaign file, its effect, its errors",
          "[methods][rounds]") {
  const MethodTable table = builtin_methods().with(test::two_round_row());
  // Lines: 1 [ensemble], 2 method, 3 n_runs, 4 master_seed, 5 [ensemble.two_round], 6 the option.
  auto text = [](const std::string& option) {
    return fmt::format("[ensemble]\nmethod = \"two_round\"\nn_runs = 100\nmaster_seed = 11\n"
                       "[ensemble.two_round]\n{}\n{}",
                       option, campaign::test::kFourBaysStrutMass);
  };
  auto error_of = [&](const std::string& t, const std::vector<std::string>& sets = {}) -> std::string {
    try {
      campaign::parse_campaign_text(t, "two.toml", ".", table, sets);
    } catch (const io::InputError& e) {
      return e.what();
    }
    return {};
  };
  // Round 0 as in the test above: mean 2, half-width h = 1.96 sqrt(100/99) / 10 = 0.197.
  std::vector<double> y;
  std::vector<std::int8_t> status;
  for (int i = 0; i < 100; ++i) {
    y.push_back(i % 2 ? 3.0 : 1.0);
    status.push_back(0);
  }
  const double h = 1.96 * std::sqrt(100.0 / 99.0) / 10.0;
  auto context = [&](const std::string& option) {
    return campaign::CampaignContext(campaign::parse_campaign_text(text(option), "two.toml", ".", table));
  };
  const campaign::CampaignContext tight = context("rel_half_width = 0.05"), loose = context("rel_half_width = 0.2"),
                                  plain = context("");
  CHECK(tight.options.ensemble.method.name() == "two_round");
  const std::unique_ptr<Method> t = table.make(tight), l = table.make(loose), p = table.make(plain);
  CHECK(t->propose(0, {}).n_runs == 100);
  const auto wanted = static_cast<std::int64_t>(std::ceil(100.0 * (h / 0.1) * (h / 0.1) - 100.0));  // 289
  CHECK(t->propose(1, records(y, status)).n_runs == wanted);
  CHECK(l->propose(0, {}).n_runs == 100);
  CHECK(l->propose(1, records(y, status)).n_runs == 0);  // target 0.4 > h
  CHECK(p->propose(0, {}).n_runs == 100);
  CHECK(p->propose(1, records(y, status)).n_runs == 300);  // the default 0.02: target 0.04, capped at 3 n0
  CHECK(campaign::calc_max_runs(tight.options) == 400);
  // Its resolved TOML reads back to the same option.
  const campaign::CampaignOptions back =
      campaign::parse_campaign_text(campaign::resolved_campaign_toml(tight.options), "resolved.toml", ".", table);
  CHECK(back.ensemble.method.as<test::TwoRoundOptions>().rel_half_width == 0.05);
  CHECK(campaign::resolved_campaign_toml(back) == campaign::resolved_campaign_toml(tight.options));
  // Bad values, named by file, line and key (or the --set).
  CHECK_THAT(error_of(text("rel_half_width = 0.0")),
             Catch::Contains("two.toml:6: ensemble.two_round.rel_half_width: must be positive and finite, got 0"));
  CHECK_THAT(error_of(text("rel_half_width = \"wide\"")),
             Catch::Contains("two.toml:6: ensemble.two_round.rel_half_width: expected a number"));
  CHECK_THAT(error_of(text("output = \"peak_drive_farce_N\"")),
             Catch::Contains("two.toml:6: ensemble.two_round.output: \"peak_drive_farce_N\" is not a float64 column"));
  CHECK_THAT(error_of(text("rel_halfwidth = 0.1")),
             Catch::Contains("two.toml:6: unknown key 'ensemble.two_round.rel_halfwidth'"));
  CHECK_THAT(error_of(text("rel_half_width = 0.05"), {"ensemble.two_round.rel_half_width=-2"}),
             Catch::Contains("--set ensemble.two_round.rel_half_width=-2: ensemble.two_round.rel_half_width: must be "
                             "positive"));
  // Its table under another method, and the method without its row, refused.
  CHECK_THAT(error_of(text("rel_half_width = 0.05"), {"ensemble.method=design"}),
             Catch::Contains("two.toml:5: ensemble.two_round: [ensemble.two_round] goes with ensemble.method = "
                             "\"two_round\", not \"design\""));
  CHECK_THAT(campaign::test::campaign_error(text("rel_half_width = 0.05"), "two.toml"),
             Catch::Contains("two.toml:2: ensemble.method: \"two_round\" is not one of \"design\", \"stop\", "
                             "\"subset\""));
}
