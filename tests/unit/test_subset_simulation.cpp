// test_subset_simulation.cpp — the state machine of subset simulation (src/sampling/): options,
// the round plan's bytes and the points computed from them, keys, save/load and resume, and the
// estimator's bookkeeping on a case whose every number follows by hand (frozen chains). The
// estimates against exact probabilities are in tests/numeric/test_subset_estimates.cpp.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "numeric/subset_cases.hpp"

using namespace truss::sampling;
using truss::sampling::normal_quantile;
using truss::testing::LinearCase;
using Catch::Matchers::Contains;

namespace {

SubsetOptions make_options(std::int64_t n, double p0, std::uint64_t seed, int dims = 10) {
  SubsetOptions o;
  o.dims = dims;
  o.n_per_level = n;
  o.p0 = p0;
  o.seed = seed;
  return o;
}

// The margins of the current round's points (linear case), computed from the round's bytes.
std::vector<double> calc_margins(const SubsetSimulation& sim, const LinearCase& c) {
  const SubsetOptions& o = sim.options();
  const SubsetRound r = SubsetRound::decode(sim.round().encode(), o.dims);
  std::vector<double> m(static_cast<std::size_t>(r.n_points)), z(static_cast<std::size_t>(o.dims));
  for (std::int64_t k = 0; k < r.n_points; ++k) {
    calc_round_uniforms(o, r, k, z.data());
    for (double& x : z) x = normal_quantile(x);
    m[static_cast<std::size_t>(k)] = c.calc_margin(z.data(), o.dims);
  }
  return m;
}

}  // namespace

TEST_CASE("Subset options: each bad field named", "[subset]") {
  CHECK(make_options(2000, 0.1, 1).validate().empty());
  CHECK(make_options(1000, 0.3, 1).validate().empty());  // 300 chains of 3 or 4 states
  CHECK_THAT(make_options(2000, 0.6, 1).validate(), Contains("p0") && Contains("(0, 0.5]"));
  CHECK_THAT(make_options(2000, 0.0, 1).validate(), Contains("p0"));
  CHECK_THAT(make_options(1001, 0.1, 1).validate(), Contains("whole number of chains"));
  CHECK_THAT(make_options(2000, 0.1, 1, 0).validate(), Contains("dims"));
  SubsetOptions o = make_options(2000, 0.1, 1);
  o.proposal_half_width = 0.0;
  CHECK_THAT(o.validate(), Contains("proposal_half_width"));
  // Outside [1e-3, 10] standard deviations the chains stand still (z + a rounds to z, or every
  // candidate has phi(e) / phi(z) = 0): refused, the value printed in full.
  for (const double a : {5e-324, 9.99e-4, 10.01, 1e308}) {
    o.proposal_half_width = a;
    CHECK_THAT(o.validate(), Contains(fmt::format("proposal_half_width: {:.17g} (must lie in [0.001, 10]", a)));
  }
  for (const double a : {1e-3, 1.0, 10.0}) {
    o.proposal_half_width = a;
    CHECK(o.validate().empty());
  }
  o = make_options(2000, 0.1, 1);
  o.max_levels = 0;
  CHECK_THAT(o.validate(), Contains("max_levels"));
  CHECK_THROWS_AS(SubsetSimulation(make_options(2000, 0.7, 1)), std::invalid_argument);
  CHECK(make_options(2000, 0.1, 1).max_evaluations() == 2000 + 19 * 1800);
}

TEST_CASE("Subset rounds: bytes round-trip, points are pure functions of (plan, index)", "[subset]") {
  const LinearCase c{3.0};
  SubsetSimulation sim(make_options(500, 0.1, 7, 4));
  // Level 0, then a Markov step.
  for (int r = 0; r < 2; ++r) {
    const SubsetRound& a = sim.round();
    const SubsetRound b = SubsetRound::decode(a.encode(), 4);
    CHECK(b.index == r);
    CHECK(b.level == a.level);
    CHECK(b.step == a.step);
    CHECK(b.n_points == a.n_points);
    CHECK(b.chains == a.chains);
    CHECK(b.first_evaluation == (r == 0 ? 0 : 500));
    std::vector<double> u1(4), u2(4);
    for (std::int64_t k = b.n_points - 1; k >= 0; --k) {  // any order, any copy: the same bits
      calc_round_uniforms(sim.options(), a, k, u1.data());
      calc_round_uniforms(sim.options(), b, k, u2.data());
      CHECK(u1 == u2);
      for (double u : u1) CHECK((u > 0.0 && u < 1.0));
    }
    CHECK_THROWS_AS(calc_round_uniforms(sim.options(), b, b.n_points, u1.data()), std::out_of_range);
    // Cut, lengthened, or mislabelled bytes are refused.
    const std::string bytes = a.encode();
    for (std::size_t cut : {std::size_t{0}, std::size_t{3}, bytes.size() / 2, bytes.size() - 1})
      CHECK_THROWS_AS(SubsetRound::decode(bytes.substr(0, cut), 4), std::runtime_error);
    CHECK_THROWS_AS(SubsetRound::decode(bytes + "x", 4), std::runtime_error);
    if (r == 1) CHECK_THROWS_AS(SubsetRound::decode(bytes, 5), std::runtime_error);  // another d
    sim.add_margins(calc_margins(sim, c));
  }
  CHECK(sim.round().step == 2);
  CHECK_THROWS_AS(sim.add_margins(std::vector<double>(3)), std::invalid_argument);
}

TEST_CASE("Subset keys: level 0's point k depends on (seed, k, dimension) only", "[subset]") {
  const SubsetSimulation small(make_options(100, 0.1, 42)), large(make_options(3000, 0.1, 42)),
      other(make_options(100, 0.1, 43));
  std::vector<double> a(10), b(10), c(10);
  calc_round_uniforms(small.options(), small.round(), 7, a.data());
  calc_round_uniforms(large.options(), large.round(), 7, b.data());
  calc_round_uniforms(other.options(), other.round(), 7, c.data());
  CHECK(a == b);
  for (int j = 0; j < 10; ++j) CHECK(a[static_cast<std::size_t>(j)] != c[static_cast<std::size_t>(j)]);
  // Level 0 is standard normal: 30,000 values, mean and variance within 5 standard errors.
  double s = 0.0, s2 = 0.0;
  std::vector<double> z(10);
  for (std::int64_t k = 0; k < 3000; ++k) {
    calc_round_normals(large.options(), large.round(), k, z.data());
    for (double x : z) {
      s += x;
      s2 += x * x;
    }
  }
  const double n = 30000.0, mean = s / n, var = s2 / n - mean * mean;
  CHECK(std::abs(mean) < 5.0 / std::sqrt(n));
  CHECK(std::abs(var - 1.0) < 5.0 * std::sqrt(2.0 / n));
}

TEST_CASE("Subset state: save/load anywhere and go on gives the same bytes", "[subset]") {
  const LinearCase c{4.0};
  const SubsetOptions o = make_options(500, 0.1, 11);
  SubsetSimulation whole(o);
  std::vector<std::string> states{whole.save()};
  while (!whole.done()) {
    whole.add_margins(calc_margins(whole, c));
    states.push_back(whole.save());
  }
  const std::string final_bytes = whole.save();
  const SubsetSummary final_summary = whole.calc_summary();
  REQUIRE(states.size() > 20);
  for (std::size_t at : {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{9}, std::size_t{10},
                         states.size() / 2, states.size() - 1}) {
    INFO("resumed after round " << at);
    SubsetSimulation resumed = SubsetSimulation::load(states[at]);
    CHECK(resumed.save() == states[at]);
    while (!resumed.done()) resumed.add_margins(calc_margins(resumed, c));
    CHECK(resumed.save() == final_bytes);
    const SubsetSummary r = resumed.calc_summary();  // what is derived from the state, not only its bytes
    CHECK(r.p == final_summary.p);
    CHECK(r.cov == final_summary.cov);
    CHECK(r.cov_lineage == final_summary.cov_lineage);
    CHECK(r.lineages == final_summary.lineages);
    CHECK(r.runs == final_summary.runs);
  }
  const std::string& mid = states[states.size() / 2];
  for (std::size_t cut : {std::size_t{2}, mid.size() / 3, mid.size() - 1})
    CHECK_THROWS_AS(SubsetSimulation::load(mid.substr(0, cut)), std::runtime_error);
  CHECK_THROWS_AS(SubsetSimulation::load(mid + "x"), std::runtime_error);
  CHECK_THROWS_AS(whole.add_margins({}), std::logic_error);
}

// Margins from level 0 only: every candidate of a Markov step gets NaN (not in any domain), so
// every chain keeps its seed. Then by hand, with m_(k) the k-th smallest level-0 margin and
// N = 2000, N_c = 200, chains of L = 10 states:
//   level 1: 200 seeds x 10 copies; b_2 = m_(20); P = 0.1; each chain's indicator is constant, so
//            rho_l = 1 and gamma = 2 sum_{l=1}^{9} (1 - l / 10) = L - 1 = 9;
//   level 2: 20 values x 100 copies; b_3 = m_(2); P = 0.1; gamma = 9;
//   level 3: 2 values x 1000 copies; b_4 = m_(1); P = 1000 / 2000 = 0.5 (800 ties); gamma = 9;
//   level 4: m_(1) x 2000: the threshold does not decrease: no_progress, P = #{<= 0} / N = 0.
TEST_CASE("Subset on frozen chains: no estimate (chains_stuck), level 0's bookkeeping by hand", "[subset]") {
  // Every Markov candidate's margin is NaN (a run that cannot say): no chain ever moves, level 1
  // only repeats level 0's 200 seeds, and the simulation ends there without an estimate.
  const LinearCase c{4.75};
  SubsetSimulation sim(make_options(2000, 0.1, 5));
  std::vector<double> level0 = calc_margins(sim, c);
  sim.add_margins(level0);
  std::sort(level0.begin(), level0.end());
  REQUIRE(level0.front() > 0.0);
  while (!sim.done()) sim.add_margins(std::vector<double>(static_cast<std::size_t>(sim.round().n_points), NAN));
  const SubsetSummary s = sim.calc_summary();
  CHECK(s.status == SubsetStatus::chains_stuck);
  CHECK_THAT(s.message, Contains("level 1: no Markov chain moved in its 1800 steps"));
  REQUIRE(s.levels.size() == 2);
  const SubsetLevel& l0 = s.levels[0];
  CHECK(l0.threshold == level0[199]);
  CHECK(l0.probability == 0.1);
  CHECK(l0.steps == 0);
  CHECK(l0.cov == Approx(std::sqrt(0.9 / 200.0)).epsilon(1e-12));
  const SubsetLevel& l1 = s.levels[1];
  CHECK(l1.steps == 1800);  // N - N_c: the 200 seeds are the chains' first states
  CHECK(l1.runs <= 1800);   // a candidate equal to its state is not evaluated
  CHECK(l1.moved == 0);
  CHECK(l1.unusable == l1.runs);  // NaN candidates are runs, never states
  CHECK(l1.acceptance() == 0.0);
  CHECK(std::isnan(l1.probability));
  CHECK(std::isnan(s.p));
  CHECK(std::isnan(s.beta));
  CHECK(std::isnan(s.cov));
  CHECK(s.rounds == 1 + 9);  // level 0, then the 9 Markov steps of chains of 10 states
  CHECK(sim.calc_failure_samples().empty());
}

TEST_CASE("Subset ends: level 0 is crude Monte Carlo; the level cap; failure samples", "[subset]") {
  // beta = 0.5: more than N_c failures at level 0, p = #{margin <= 0} / N (counted here).
  SubsetSimulation mc(make_options(1000, 0.1, 3));
  const std::vector<double> m = calc_margins(mc, LinearCase{0.5});
  mc.add_margins(m);
  const double p = static_cast<double>(std::count_if(m.begin(), m.end(), [](double x) { return x <= 0.0; })) / 1000.0;
  SubsetSummary s = mc.calc_summary();
  CHECK(s.status == SubsetStatus::converged);
  CHECK(s.p == p);
  CHECK(s.cov == Approx(std::sqrt((1.0 - p) / (1000.0 * p))).epsilon(1e-12));
  CHECK(s.cov_lineage == Approx(s.cov).epsilon(1e-9));  // one level of independent samples: the same
  CHECK(s.runs == 1000);
  CHECK(s.rounds == 1);
  CHECK(static_cast<double>(mc.calc_failure_samples().size()) == p * 1000.0);

  // The cap: two levels for p = 1e-6: the estimate is p0 times level 1's failure fraction.
  SubsetOptions o = make_options(2000, 0.1, 3);
  o.max_levels = 2;
  const LinearCase deep{4.75};
  SubsetSimulation capped(o);
  while (!capped.done()) capped.add_margins(calc_margins(capped, deep));
  s = capped.calc_summary();
  CHECK(s.status == SubsetStatus::level_cap);
  CHECK_THAT(s.message, Contains("max_levels = 2"));
  REQUIRE(s.levels.size() == 2);
  CHECK(s.p == Approx(0.1 * s.levels[1].probability).epsilon(1e-15));
  CHECK(s.runs <= o.max_evaluations());

  // Failure samples of a converged run: distinct evaluations, each failing at its own point.
  const LinearCase c3{3.0};
  SubsetSimulation sim(make_options(2000, 0.1, 4));
  while (!sim.done()) sim.add_margins(calc_margins(sim, c3));
  s = sim.calc_summary();
  const auto failures = sim.calc_failure_samples();
  REQUIRE(!failures.empty());
  CHECK(static_cast<double>(failures.size()) <= s.levels.back().probability * 2000.0);
  for (std::size_t i = 0; i < failures.size(); ++i) {
    CHECK(failures[i].margin <= 0.0);
    // The stored margin came from the uniforms Phi(z): the same point to ~1e-15.
    CHECK(c3.calc_margin(failures[i].z.data(), 10) == Approx(failures[i].margin).margin(1e-9));
    CHECK(failures[i].evaluation < s.runs);
    if (i > 0) CHECK(failures[i].evaluation > failures[i - 1].evaluation);
  }
}

TEST_CASE("Subset in one dimension: a step whose candidate equals its state is not evaluated", "[subset]") {
  SubsetSimulation sim(make_options(1000, 0.1, 9, 1));
  while (!sim.done()) sim.add_margins(calc_margins(sim, LinearCase{3.0}));
  const SubsetSummary s = sim.calc_summary();
  std::int64_t runs = 0, steps = 0;
  for (const SubsetLevel& l : s.levels) {
    runs += l.runs;
    steps += l.steps;
    CHECK(l.moved <= l.runs);
  }
  CHECK(runs == s.runs);
  CHECK(s.runs - 1000 < steps);  // some proposals rejected in their only dimension: no run
  CHECK(steps == static_cast<std::int64_t>(s.levels.size() - 1) * 900);
}
