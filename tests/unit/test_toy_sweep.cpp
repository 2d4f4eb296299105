// test_toy_sweep.cpp — a method added as its file and one row (tests/methods/toy_failure.hpp) is
// swept like the built-in ones: "can be swept" is "has a [failure] event", checked when the campaign
// is read, and the sweep (methods/sweep_method.hpp) holds one such method per design value. The
// engine's loop runs here in one process; each run's column is its dispersed stall torque x + sigma Z
// (calc_run_inputs: the same number the synthetic runs of the MPI tests record), which fails below
// 3.5 mN m. Expected values from the runs themselves: each value's p is the share of its runs at or
// below the threshold, counted here, and its runs are the standalone campaign's, point for point.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <string>

#include <fmt/format.h>

#include "campaign/design_axis.hpp"
#include "campaign_fixtures.hpp"
#include "methods/failure_count.hpp"
#include "methods/stop_method.hpp"
#include "methods/sweep_method.hpp"
#include "methods/toy_failure.hpp"
#include "methods/two_round.hpp"

using namespace truss;

namespace {

const char* kToySweep = R"([ensemble]
method = "toy"
n_runs = 400
master_seed = 3
[ensemble.toy]
first_share = 0.25
[failure]
column = "motor_torque_margin_Nm"
below = 0.0035
unit = "Nm"
[sweep]
key = "drive.stall_torque_Nm"
values = [0.004, 0.0045, 0.005, 0.0055]
target_probability = 0.05
safe_side = "above"
[[dispersion]]
key = "drive.stall_torque_Nm"
apply = "offset"
distribution = "normal"
std = 0.001
)";

// Every run the method proposes, as the engine makes them: the points of each round's plan, the
// run's column (its applied stall torque), the records in run order to the next propose().
struct Runs {
  std::vector<double> column;    // by run index
  std::vector<double> design_u;  // the design coordinate (NaN without a sweep)
};
Runs run_rounds(methods::Method& m, const campaign::CampaignContext& ctx) {
  Runs out;
  methods::RoundRecords previous;
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  for (std::int64_t round = 0, first = 0;; ++round) {
    const methods::Proposal p = m.propose(round, previous);
    if (p.n_runs == 0) return out;
    const methods::RoundPlan plan{round, first, p.n_runs, p.state};
    previous = methods::RoundRecords{first, {}, {{}}};
    for (std::int64_t run = first; run < plan.end_run(); ++run) {
      m.calc_uniforms(plan, run, u.data());
      const double x = campaign::calc_run_inputs(ctx.options, ctx.dims, u.data()).values[0][0];
      out.column.push_back(x);
      out.design_u.push_back(ctx.dims.design >= 0 ? u[static_cast<std::size_t>(ctx.dims.design)] : std::nan(""));
      previous.status.push_back(static_cast<std::int8_t>(sim::RunStatus::ok));
      previous.outputs[0].push_back(x);
    }
    first = plan.end_run();
  }
}

const methods::MethodTable& toy_table() {
  static const methods::MethodTable t = methods::builtin_methods().with(test::toy_row()).with(test::two_round_row());
  return t;
}

}  // namespace

TEST_CASE("a toy method with a [failure] event sweeps end to end; each value is its campaign alone", "[sweep][toy]") {
  const campaign::CampaignContext ctx(campaign::parse_campaign_text(kToySweep, "toy.toml", ".", toy_table()));
  REQUIRE(ctx.options.ensemble.method.name() == "sweep");
  REQUIRE(ctx.options.ensemble.method.options().inner_method()->name() == "toy");
  std::unique_ptr<methods::Method> sweep = toy_table().make(ctx);
  const Runs all = run_rounds(*sweep, ctx);
  const auto& s = dynamic_cast<const methods::SweepMethod&>(*sweep);
  const std::vector<methods::SweepMethod::ValueResult> values = s.calc_value_results();
  const campaign::DesignAxis& axis = *campaign::find_design_axis(ctx.options);
  REQUIRE(values.size() == axis.n_values());
  CHECK(all.column.size() == 400 * axis.n_values());
  for (const methods::SweepMethod::ValueResult& v : values) {
    INFO("value " << v.index);
    // Its runs: the design coordinate (k + 0.5) / n; p the share of them at or below 3.5 mN m.
    std::vector<double> mine;
    for (std::size_t i = 0; i < all.column.size(); ++i)
      if (all.design_u[i] == (static_cast<double>(v.index) + 0.5) / static_cast<double>(axis.n_values()))
        mine.push_back(all.column[i]);
    std::int64_t failing = 0;
    for (double x : mine) failing += x <= 0.0035 ? 1 : 0;
    CHECK(mine.size() == 400);
    CHECK(v.estimate.runs == 400);
    CHECK(v.estimate.failures == failing);
    CHECK(v.estimate.bounds.p == static_cast<double>(failing) / 400.0);
    // The campaign alone at that value: the same points in the same order, the same estimate.
    const campaign::CampaignContext at(campaign::calc_campaign_at(ctx.options, v.index));
    CHECK(campaign::find_design_axis(at.options) == nullptr);
    std::unique_ptr<methods::Method> alone = toy_table().make(at);
    CHECK(run_rounds(*alone, at).column == mine);
    const methods::FailureEstimate e = *alone->calc_failure_estimate(0.95);
    CHECK(e.bounds.upper_bound == v.estimate.bounds.upper_bound);
    CHECK(e.failures == v.estimate.failures);
  }
  // p falls as the stall torque grows (Phi((3.5 - x) / 1 mN m): 0.31 to 0.023): the allowable's
  // safe side is above, and the verdict compares it with the campaign's own torque.
  const methods::SweepVerdict verdict =
      methods::calc_sweep_verdict(ctx.options, ctx.options.ensemble.method.as<methods::SweepOptions>(), values);
  REQUIRE(verdict.allowable.status == sampling::AllowableStatus::found);
  CHECK(verdict.allowable.safe_side > 0);
  CHECK(verdict.own_value == ctx.options.base.drive.stall_torque_Nm);
  CHECK(verdict.verdict == (verdict.own_value >= verdict.allowable.value ? "PASS" : "FAIL"));
  CHECK_THAT(verdict.reason, Catch::Contains(verdict.verdict == "PASS" ? "on the safe side" : "on the unsafe side"));
  // One untrusted value and the allowable is not read: NOT ASSESSED, its reason naming the value.
  std::vector<methods::SweepMethod::ValueResult> one_untrusted = values;
  one_untrusted[1].estimate.untrusted = "3 of 100 runs have no usable result";
  const methods::SweepVerdict not_read = methods::calc_sweep_verdict(
      ctx.options, ctx.options.ensemble.method.as<methods::SweepOptions>(), one_untrusted);
  CHECK(not_read.verdict == "NOT ASSESSED");
  CHECK(std::isnan(not_read.allowable.value));
  CHECK_THAT(not_read.reason, Catch::Contains(fmt::format("at {:.6g} ", one_untrusted[1].value)) &&
                                  Catch::Contains("3 of 100 runs have no usable result"));
}

TEST_CASE("an estimate is untrusted past 1 % unusable runs", "[sweep][toy]") {
  CHECK(methods::find_unusable_reason(0, 100).empty());
  CHECK(methods::find_unusable_reason(1, 100).empty());  // 1 % exactly: stands
  CHECK_THAT(methods::find_unusable_reason(2, 100), Catch::Contains("2 of 100 runs have no usable result"));
  CHECK_THAT(methods::find_unusable_reason(1, 99), Catch::Contains("more than 1 %"));
}

TEST_CASE("can be swept = has a [failure] event, refused when the file is read", "[sweep][toy]") {
  auto error_of = [](const std::string& text) {
    try {
      campaign::parse_campaign_text(text, "toy.toml", ".", toy_table());
    } catch (const io::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // The toy without [failure] (its own rule), and a method with no failure event at all.
  std::string no_failure = kToySweep;
  no_failure.erase(no_failure.find("[failure]"), no_failure.find("[sweep]") - no_failure.find("[failure]"));
  CHECK_THAT(error_of(no_failure), Catch::Contains("failure: a sweep estimates the probability of a [failure] event"));
  std::string two_round = no_failure;
  two_round.replace(two_round.find("method = \"toy\""), 14, "method = \"two_round\"");
  two_round.replace(two_round.find("[ensemble.toy]\nfirst_share = 0.25\n"), 34, "");
  CHECK_THAT(error_of(two_round),
             Catch::Contains("toy.toml:2: ensemble.method: \"two_round\" estimates no failure probability"));
  // Its table's keys as every table's: typed, in range, an unknown one with a suggestion.
  std::string bad = kToySweep;
  bad.replace(bad.find("first_share = 0.25"), 18, "first_share = 1.5");
  CHECK_THAT(error_of(bad), Catch::Contains("toy.toml:6: ensemble.toy.first_share: must lie in (0, 1), got 1.5"));
  bad.replace(bad.find("first_share = 1.5"), 17, "first_shar = 0.5");
  CHECK_THAT(error_of(bad), Catch::Contains("toy.toml:6: unknown key 'ensemble.toy.first_shar'; did you mean "
                                            "ensemble.toy.first_share?"));
}

TEST_CASE("the built-in methods with a [failure] event count the runs that fail it", "[sweep][failure]") {
  // 100 runs: 10 with a margin at or below 0 (one of them stalled: it shows the failure), 5 that
  // stalled (runs 7, 27, 47, 67, 87), the 4 with a positive margin unusable (they cannot say: never
  // safe). Monte Carlo's p is 10 / 96 over the usable runs, and 4 % unusable is past 1 %: untrusted.
  // The stop rule's own share stays 10 / 100; a stop rule without [failure] counts the 5 runs that
  // are not ok instead.
  methods::RoundRecords r{0, {}, {{}}};
  for (int i = 0; i < 100; ++i) {
    r.status.push_back(static_cast<std::int8_t>(i % 20 == 7 ? sim::RunStatus::stall : sim::RunStatus::ok));
    r.outputs[0].push_back(i < 10 ? -0.001 * i : 0.001 + 0.001 * i);
  }
  const std::string base = "[ensemble]\nn_runs = 100\n[[dispersion]]\nkey = \"drive.speed_m_per_s\"\n"
                           "distribution = \"normal\"\nstd = 0.05\n";
  const std::string failure = "[failure]\nmargin = \"motor_torque_margin_Nm\"\n";
  const std::string stop = "[ensemble.stop]\ntarget = \"probability_half_width\"\nwidth = 0.3\nmax_runs = 1000\n";
  for (const std::string& text : {base + failure, base + failure + stop, base + stop}) {
    const campaign::CampaignContext ctx(campaign::parse_campaign_text(text, "f.toml", ".", toy_table()));
    std::unique_ptr<methods::Method> m = toy_table().make(ctx);
    INFO(text);
    const bool event = text.find("[failure]") != std::string::npos;
    CHECK(m->observed_outputs() == (event ? std::vector<std::string>{"motor_torque_margin_Nm"}
                                          : std::vector<std::string>{}));
    CHECK(m->propose(0, {}).n_runs == 100);
    methods::RoundRecords given = r;
    if (!event) given.outputs.clear();
    m->propose(1, given);
    const std::optional<methods::FailureEstimate> e = m->calc_failure_estimate(0.95);
    CHECK(e.has_value() == event);
    if (e) {
      CHECK(e->runs == 100);
      CHECK(e->failures == 10);
      CHECK(e->bounds.p == 10.0 / 96.0);
      CHECK(e->unusable == 4);
      CHECK_THAT(e->untrusted, Catch::Contains("4 of 100 runs have no usable result"));
      CHECK(e->nearest_margin == -0.001 * 9);  // the smallest margin, as the runs gave it
    }
    if (text.find("[ensemble.stop]") != std::string::npos) {
      const auto& decisions = dynamic_cast<const methods::StopMethod&>(*m).decisions();
      REQUIRE(decisions.size() == 1);
      CHECK(decisions[0].estimate == (event ? 0.1 : 0.05));
    }
  }
}
