// test_subset_adaptive.cpp — adaptive conditional sampling and the lag CoV of subset simulation
// (src/sampling/subset_simulation.hpp) on a case small enough to follow by hand: N = 6 samples a
// level, p0 = 1/3 (two chains of three states), one dimension, every margin given by the test.
// The candidates, the scale lambda after each step and the lag CoVs are computed here from the
// header's formulas and the documented keys, independently of the state machine's bookkeeping.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "numeric/subset_cases.hpp"
#include "sampling/subset_keys.hpp"

using namespace truss::sampling;

namespace {

SubsetOptions make_hand_options() {
  SubsetOptions o;
  o.dims = 1;
  o.n_per_level = 6;
  o.p0 = 1.0 / 3.0;
  o.max_levels = 5;
  o.seed = 77;
  o.proposal = SubsetProposal::adaptive_conditional;
  return o;
}

// The candidate of chain c at (level, step) from state z with spread sigma (header, "adaptive step").
double calc_expected_candidate(const SubsetOptions& o, int level, int step, std::int64_t chain, double z,
                               double sigma) {
  const std::uint64_t state = counter_run_state(o.seed, chain, subset_stream(level, step, kStreamPropose));
  const double n = normal_quantile(to_open_unit(splitmix_at(state, 0)));
  return std::sqrt(1.0 - sigma * sigma) * z + sigma * n;
}

double calc_sample_sd(double a, double b) { return std::abs(a - b) / std::sqrt(2.0); }  // n - 1 = 1

}  // namespace

// Level 0: margins 3 1 4 2 5 6: b_1 = 2 (the 2nd smallest), P_0 = 1/3, seeds samples 1 and 3.
// Level 1 (domain <= 2): chain 0 from sample 1 (margin 1) steps to 0.5 (kept) and 0.2 (kept); chain 1
//   from sample 3 (margin 2) to 7 (refused: stays 2) and 1.5 (kept). Margins 1 2 0.5 2 0.2 1.5 in
//   creation order: b_2 = 0.5, P_1 = 1/3; the seeds are chain 0's two steps (one parent).
// Level 2 (domain <= 0.5): chain 0 from 0.5 to -1 and -0.5, chain 1 from 0.2 to 0.1 and 0.4, all
//   kept: the 2nd smallest is -0.5 <= 0: P_2 = #{<= 0} / 6 = 1/3, p = 1/27.
// Terms (I - P) / (N P) = (I - 1/3) / 2: level 0 a = -1/6, 1/3, -1/6, 1/3, -1/6, -1/6; level 1 chain
// sums T_1 = (1/2, -1/2); level 2 T_2 = (1/2, -1/2). Lag 0 groups each level by its own units: 1/3 +
// 1/2 + 1/2 = 4/3 (no cross term: level 1 over the roots is (1/2 at sample 1, -1/2 at 3), against
// a = 1/3 at both; level 2 over level 1's chain 0 is 0). Lag 1 groups level 2 by its parent chain:
// both chains have one parent, so C_22 = (1/2 - 1/2)^2 = 0: 1/3 + 1/2 = 5/6, also the lineage CoV
// (per root: 1/3 + 1/2 at sample 1, 1/3 - 1/2 at 3, -1/6 at the other four: 25/36 + 5/36 = 5/6).
// lambda: 0.6, then after each step (a - 0.44) / sqrt(step): level 1 a = 1/2, then 1; level 2 1, 1.
TEST_CASE("Adaptive conditional sampling by hand: candidates, lambda, lag CoVs", "[subset][adaptive]") {
  const SubsetOptions o = make_hand_options();
  SubsetSimulation sim(o);
  std::vector<double> z0(6);
  for (std::int64_t k = 0; k < 6; ++k) calc_round_normals(o, sim.round(), k, &z0[static_cast<std::size_t>(k)]);
  sim.add_margins(std::vector<double>{3, 1, 4, 2, 5, 6});
  double lambda = SubsetOptions::kInitialScale;
  // Level 1: seeds z0[1], z0[3]; sigma0 their sample standard deviation.
  const double sd1 = calc_sample_sd(z0[1], z0[3]);
  std::vector<double> state{z0[1], z0[3]};
  const std::vector<std::vector<double>> margins1{{0.5, 7.0}, {0.2, 1.5}};
  for (int step = 1; step <= 2; ++step) {
    const SubsetRound& r = sim.round();
    REQUIRE(r.level == 1);
    REQUIRE(r.step == step);
    REQUIRE(r.n_points == 2);  // conditional sampling evaluates every step of every chain
    const double sigma = std::min(1.0, lambda * sd1);
    std::vector<double> cand(2);
    for (int c = 0; c < 2; ++c) {
      cand[static_cast<std::size_t>(c)] = calc_expected_candidate(o, 1, step, c, state[static_cast<std::size_t>(c)],
                                                                 sigma);
      CHECK(r.z[static_cast<std::size_t>(c)] == Approx(cand[static_cast<std::size_t>(c)]).epsilon(1e-14));
    }
    const std::vector<double>& m = margins1[static_cast<std::size_t>(step - 1)];
    int kept = 0;
    for (int c = 0; c < 2; ++c)
      if (m[static_cast<std::size_t>(c)] <= 2.0) {
        state[static_cast<std::size_t>(c)] = cand[static_cast<std::size_t>(c)];
        ++kept;
      }
    lambda *= std::exp((kept / 2.0 - SubsetOptions::kTargetAcceptance) / std::sqrt(step));
    sim.add_margins(m);
  }
  // Level 2: the seeds are chain 0's two steps (margins 0.5 and 0.2), in creation order.
  {
    const SubsetSummary s = sim.calc_summary();
    REQUIRE(s.levels.size() == 2);
    CHECK(s.levels[1].threshold == 0.5);
    CHECK(s.levels[1].probability == Approx(1.0 / 3.0).epsilon(1e-15));
    CHECK(s.levels[1].scale == Approx(lambda).epsilon(1e-14));
  }
  const SubsetRound& r2 = sim.round();
  REQUIRE(r2.level == 2);
  const std::vector<std::vector<double>> margins2{{-1.0, 0.1}, {-0.5, 0.4}};
  for (int step = 1; step <= 2; ++step) {
    REQUIRE(sim.round().n_points == 2);
    lambda *= std::exp((1.0 - SubsetOptions::kTargetAcceptance) / std::sqrt(step));
    sim.add_margins(margins2[static_cast<std::size_t>(step - 1)]);
  }
  REQUIRE(sim.done());
  const SubsetSummary s = sim.calc_summary();
  CHECK(s.status == SubsetStatus::converged);
  CHECK(s.p == Approx(1.0 / 27.0).epsilon(1e-14));
  CHECK(s.levels[2].scale == Approx(lambda).epsilon(1e-14));
  CHECK(sim.calc_lag_cov(0) == Approx(std::sqrt(4.0 / 3.0)).epsilon(1e-14));
  CHECK(sim.calc_lag_cov(1) == Approx(std::sqrt(5.0 / 6.0)).epsilon(1e-14));
  CHECK(sim.calc_lag_cov(-1) == Approx(std::sqrt(5.0 / 6.0)).epsilon(1e-14));
  CHECK(s.cov_lineage == Approx(std::sqrt(5.0 / 6.0)).epsilon(1e-14));
  CHECK(s.cov_lag1 == Approx(std::sqrt(5.0 / 6.0)).epsilon(1e-14));
  // The roots' terms 5/6, -1/6 x 5: G = (30/36)^2 / (625 + 5) x 1296 = 900 / 630.
  CHECK(s.lineage_groups == Approx(900.0 / 630.0).epsilon(1e-13));
  // The interval's variance of ln p^: (G ln(1 + cov_lag1^2) + 2 ln(1 + cov_bound^2)) / (G + 2).
  const double g = 900.0 / 630.0, s1 = std::log1p(5.0 / 6.0), sb = std::log1p(s.cov_bound * s.cov_bound);
  CHECK(std::log1p(s.cov_interval * s.cov_interval) == Approx((g * s1 + 2.0 * sb) / (g + 2.0)).epsilon(1e-13));
}

// The scale after a step is a function of that step's count of kept candidates, never of the order
// its results come in (on N ranks they arrive in any order; adapting after each result as it comes,
// as a sequential aCS adapts after each group of chains, makes lambda depend on that order). Two
// simulations whose first step of level 1 keeps one candidate of two, chain 0's in one and chain
// 1's in the other, reach the same lambda: 0.6 exp((1/2 - 0.44) / 1) exp((1 - 0.44) / sqrt(2)) after
// the second step keeps both; adapting per result in the round's order would give
// exp(0.56 - 0.44 / sqrt(2)) against exp(-0.44 + 0.56 / sqrt(2)) for the first step.
TEST_CASE("Adaptive conditional sampling: lambda from a step's counts, not its results' order", "[subset][adaptive]") {
  const SubsetOptions o = make_hand_options();
  const double want = SubsetOptions::kInitialScale * std::exp((0.5 - SubsetOptions::kTargetAcceptance) / 1.0) *
                      std::exp((1.0 - SubsetOptions::kTargetAcceptance) / std::sqrt(2.0));
  std::vector<double> scales;
  for (const std::vector<double>& first_step : {std::vector<double>{0.5, 7.0}, std::vector<double>{7.0, 1.5}}) {
    SubsetSimulation sim(o);
    sim.add_margins(std::vector<double>{3, 1, 4, 2, 5, 6});  // level 0: b_1 = 2
    REQUIRE(sim.round().level == 1);
    sim.add_margins(first_step);                   // one of two kept
    sim.add_margins(std::vector<double>{0.2, 1.2});  // both kept: the level ends
    const SubsetSummary s = sim.calc_summary();
    REQUIRE(s.levels.size() == 2);
    scales.push_back(s.levels[1].scale);
  }
  CHECK(scales[0] == Approx(want).epsilon(1e-14));
  CHECK(scales[1] == scales[0]);
}

// The adaptation is a function of each round's counts, so of the plan: the state saved after any
// round and resumed gives the same bytes, and lambda heads for the acceptance of 0.44 (on the
// linear case in 10 dimensions the later levels' acceptance lies within 0.3 to 0.6).
TEST_CASE("Adaptive conditional sampling: resume anywhere, acceptance near its target", "[subset][adaptive]") {
  SubsetOptions o;
  o.dims = 10;
  o.n_per_level = 500;
  o.p0 = 0.1;
  o.seed = 12;
  o.proposal = SubsetProposal::adaptive_conditional;
  const truss::testing::LinearCase c{4.0};
  SubsetSimulation whole(o);
  std::vector<std::string> states{whole.save()};
  std::vector<double> u(10), m;
  const auto margins = [&](const SubsetSimulation& sim) {
    const SubsetRound r = SubsetRound::decode(sim.round().encode(), o.dims);
    m.assign(static_cast<std::size_t>(r.n_points), 0.0);
    for (std::int64_t k = r.n_points - 1; k >= 0; --k) {  // evaluated in any order
      calc_round_normals(o, r, k, u.data());
      m[static_cast<std::size_t>(k)] = c.calc_margin(u.data(), o.dims);
    }
    return m;
  };
  while (!whole.done()) {
    whole.add_margins(margins(whole));
    states.push_back(whole.save());
  }
  const SubsetSummary final_summary = whole.calc_summary();
  REQUIRE(final_summary.status == SubsetStatus::converged);
  for (std::size_t at : {std::size_t{1}, std::size_t{3}, states.size() / 2, states.size() - 2}) {
    INFO("resumed after round " << at);
    SubsetSimulation resumed = SubsetSimulation::load(states[at]);
    CHECK(resumed.save() == states[at]);
    while (!resumed.done()) resumed.add_margins(margins(resumed));
    CHECK(resumed.save() == states.back());
    CHECK(resumed.calc_summary().cov_interval == final_summary.cov_interval);
  }
  for (std::size_t k = 2; k < final_summary.levels.size(); ++k) {
    INFO("level " << k);
    CHECK(final_summary.levels[k].acceptance() > 0.3);
    CHECK(final_summary.levels[k].acceptance() < 0.6);
    CHECK(final_summary.levels[k].runs == 450);  // every step evaluated
  }
  // Another proposal is another state: a saved adaptive state does not load as the other.
  std::string other = states[2];
  other[8] = static_cast<char>(7);  // the proposal's int32 after the tag and dims
  CHECK_THROWS_AS(SubsetSimulation::load(other), std::runtime_error);
}

// The trust rule (find_untrusted_reason): the statuses that end short of the failure, and plateau
// levels (b_k > 0 moving by less than 1 % of b_k to b_{k+1}) from three on; the thresholds by hand.
TEST_CASE("Subset estimates that must not feed an allowable, and why", "[subset][trust]") {
  SubsetSummary s;
  s.status = SubsetStatus::converged;
  for (double b : {0.2, 0.1059, 0.1055, 0.1052, 0.1050, 0.05, 0.0}) {
    SubsetLevel l;
    l.threshold = b;
    s.levels.push_back(l);
  }
  // 0.1059 -> 0.1055 (0.38 %), 0.1055 -> 0.1052, 0.1052 -> 0.1050: three plateau levels; 0.2 -> 0.1059
  // and 0.1050 -> 0.05 are not, nor is the last (b = 0).
  CHECK(s.calc_plateau_levels() == 3);
  CHECK_THAT(find_untrusted_reason(s), Catch::Matchers::Contains("nearly flat over 3 levels"));
  s.levels[4].threshold = 0.1040;  // 0.1052 -> 0.1040 is 1.14 %: two plateau levels
  CHECK(s.calc_plateau_levels() == 2);
  CHECK(find_untrusted_reason(s).empty());
  s.status = SubsetStatus::level_cap;
  CHECK(find_untrusted_reason(s).empty());  // stands: the last level's share bounds p from above
  s.status = SubsetStatus::no_progress;
  CHECK_THAT(find_untrusted_reason(s), Catch::Matchers::Contains("stopped decreasing"));
  s.status = SubsetStatus::chains_stuck;
  CHECK_THAT(find_untrusted_reason(s), Catch::Matchers::Contains("no estimate"));
}
