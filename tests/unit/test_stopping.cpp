// test_stopping.cpp — the sequential stopping rules (src/sampling/stopping.hpp) against values
// computed independently with scipy 1.10.1: scipy.stats.beta.ppf for Clopper-Pearson (the
// report's own formula, postproc/truss_report/stats.py) and scipy.stats.binom.cdf for the
// order-statistic ranks (postproc/truss_report/design.py, upper_bound_rank). Boost.Math and scipy
// both invert the incomplete beta function to a few ulps; 1e-10 relative leaves room for their
// different iteration ends and nothing for a wrong tail (a = 0.05 instead of 0.025 moves the
// bounds by 10 % and more).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "sampling/stopping.hpp"

using namespace truss::sampling;
using Catch::Matchers::Contains;

namespace {

constexpr double kRel = 1e-10;

StopRule make_rule(StopTarget t, double width, std::int64_t max_runs) {
  StopRule r;
  r.target = t;
  r.width = width;
  r.max_runs = max_runs;
  return r;
}

}  // namespace

TEST_CASE("Clopper-Pearson intervals match scipy's beta quantiles", "[stop]") {
  struct Case { std::int64_t k, n; double confidence, lo, hi; };
  const Case cases[] = {{0, 10, 0.95, 0.0, 0.30849710781876077},
                        {3, 20, 0.95, 0.032070937185463715, 0.37892682654531396},
                        {7, 100000, 0.95, 2.81440788050368e-05, 0.00014422140092234864},
                        {0, 2218, 0.95, 0.0, 0.0016617734731721923},
                        {50, 50, 0.95, 0.92887826353580238, 1.0},
                        {1, 1000000, 0.95, 2.5317807663794201e-08, 5.5716306551669393e-06},
                        {12, 345, 0.99, 0.014455530336240771, 0.06875775686089429}};
  for (const Case& c : cases) {
    INFO(c.k << " of " << c.n << " at " << c.confidence);
    const Interval ci = calc_clopper_pearson(c.k, c.n, c.confidence);
    CHECK(ci.lo == Approx(c.lo).epsilon(kRel).margin(0.0));
    CHECK(ci.hi == Approx(c.hi).epsilon(kRel).margin(0.0));
  }
  CHECK_THROWS_AS(calc_clopper_pearson(3, 2, 0.95), std::invalid_argument);
  CHECK_THROWS_AS(calc_clopper_pearson(0, 0, 0.95), std::invalid_argument);
  CHECK_THROWS_AS(calc_clopper_pearson(1, 2, 1.0), std::invalid_argument);
}

TEST_CASE("Order-statistic upper bounds: ranks as scipy's binomial CDF gives them", "[stop]") {
  // (n, q, confidence) -> the least k with F_Binomial(k - 1; n, q) >= confidence (0: none).
  CHECK(calc_upper_bound_rank(2218, 0.99865, 0.95) == 2218);
  CHECK(calc_upper_bound_rank(2217, 0.99865, 0.95) == 0);
  CHECK(calc_upper_bound_rank(5000, 0.99865, 0.95) == 4998);
  CHECK(calc_upper_bound_rank(100000, 0.99865, 0.95) == 99885);
  CHECK(calc_upper_bound_rank(10000, 0.99, 0.95) == 9917);
  CHECK(calc_upper_bound_rank(1000, 0.5, 0.95) == 527);
  CHECK(calc_upper_bound_rank(300, 0.95, 0.9) == 291);
  CHECK(calc_upper_bound_rank(0, 0.5, 0.95) == 0);
  // The least n with 1 - q^n >= confidence: 2218 for P99.865 at 95 % (the report's figure);
  // 59 for P95 at 95 % (0.95^58 = 0.0510, 0.95^59 = 0.0485).
  CHECK(calc_runs_for_upper_bound(0.99865, 0.95) == 2218);
  CHECK(calc_runs_for_upper_bound(0.95, 0.95) == 59);
  CHECK(calc_runs_for_upper_bound(0.5, 0.7) == 2);  // 1 - 0.5 < 0.7 <= 1 - 0.25
  for (double q : {0.9, 0.99, 0.99865, 0.999})
    CHECK(calc_upper_bound_rank(calc_runs_for_upper_bound(q, 0.95), q, 0.95) ==
          calc_runs_for_upper_bound(q, 0.95));  // at the least n, the only bound is the maximum
}

TEST_CASE("Percentiles are numpy's default (linear, type 7)", "[stop]") {
  // numpy.percentile of numpy.random.default_rng(1).exponential(size=7), sorted here.
  const std::vector<double> x = {0.11536203910680366, 0.30845314412528435, 0.36642711289983193, 0.498639097854449,
                                 1.0730290263725388, 1.7997970856557877, 5.375436872608127};
  CHECK(calc_percentile_sorted(x, 0.99865) == Approx(5.346474190333811).epsilon(1e-14));
  CHECK(calc_percentile_sorted(x, 0.5) == 0.498639097854449);
  CHECK(calc_percentile_sorted(x, 0.0) == x.front());
  CHECK(calc_percentile_sorted(x, 1.0) == x.back());
  CHECK(std::isnan(calc_percentile_sorted({}, 0.5)));
}

TEST_CASE("Stop rules that no outcome can meet are refused", "[stop]") {
  StopRule r = make_rule(StopTarget::percentile_bound, 0.05, 2000);
  CHECK_THAT(r.validate(), Contains("max_runs") && Contains("2218"));
  r.max_runs = 2218;
  CHECK(r.validate().empty());
  r.level = 1.0;
  CHECK_THAT(r.validate(), Contains("level"));
  // Half-width: the narrowest interval 1000 runs give is (1 - 0.025^(1/1000)) / 2 = 0.001841.
  r = make_rule(StopTarget::probability_half_width, 1e-3, 1000);
  CHECK_THAT(r.validate(), Contains("width") && Contains("0.00184"));
  r.width = 0.002;
  CHECK(r.validate().empty());
  r = make_rule(StopTarget::probability_relative_half_width, 1e-3, 1000);
  CHECK_THAT(r.validate(), Contains("relative half-width"));
  r.confidence = 1.0;
  CHECK_THAT(r.validate(), Contains("confidence"));
  r = make_rule(StopTarget::probability_half_width, -0.1, 1000);
  CHECK_THAT(r.validate(), Contains("width"));
  r = make_rule(StopTarget::probability_half_width, 0.1, 0);
  CHECK_THAT(r.validate(), Contains("max_runs"));
}

TEST_CASE("Failure-probability stop: met, more runs sized by n^-1/2, capped", "[stop]") {
  // 3 of 20: [0.032071, 0.378927], half-width 0.173428.
  StopRule r = make_rule(StopTarget::probability_half_width, 0.2, 1000);
  StopDecision d = decide_probability_stop(r, 3, 20);
  CHECK(d.state == StopState::met);
  CHECK(d.achieved == Approx(0.5 * (0.37892682654531396 - 0.032070937185463715)).epsilon(kRel));
  CHECK(d.next_runs == 0);
  // Width 0.1: 20 (0.173428 / 0.1)^2 = 60.15 -> 61 runs in all, 41 more.
  r.width = 0.1;
  d = decide_probability_stop(r, 3, 20);
  CHECK(d.state == StopState::more);
  CHECK(d.next_runs == 41);
  // Width 0.01: 20 * 300.8 runs, held to 4 n = 80: 60 more.
  r.width = 0.01;
  CHECK(decide_probability_stop(r, 3, 20).next_runs == 60);
  // Relative: no failure yet, the relative width is unknown: 4 n.
  r = make_rule(StopTarget::probability_relative_half_width, 0.5, 100000);
  d = decide_probability_stop(r, 0, 1000);
  CHECK(d.state == StopState::more);
  CHECK(std::isinf(d.achieved));
  CHECK(d.next_runs == 3000);
  // The cap: never past max_runs, and capped once there.
  r.max_runs = 2500;
  CHECK(decide_probability_stop(r, 0, 1000).next_runs == 1500);
  d = decide_probability_stop(r, 0, 2500);
  CHECK(d.state == StopState::capped);
  CHECK(d.next_runs == 0);
  CHECK_THAT(d.reason, Contains("max_runs = 2500"));
}

TEST_CASE("Percentile stop: the bound's existence, then its relative width", "[stop]") {
  StopRule r = make_rule(StopTarget::percentile_bound, 0.01, 100000);
  // 2000 runs, 100 without a value: 1900 values, 318 more needed, at 2000/1900 runs per value: 335.
  std::vector<double> v(2000);
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = i < 100 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(i);
  StopDecision d = decide_percentile_stop(r, v);
  CHECK(d.state == StopState::more);
  CHECK(d.used == 1900);
  CHECK(d.bound_rank == 0);
  CHECK(d.next_runs == 335);
  CHECK_THAT(d.reason, Contains("2218"));
  // Values 1..2218: estimate 1 + 2217 q = 2215.00705, bound x_(2218) = 2218, relative width 0.001351.
  v.resize(2218);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>(v.size() - i);  // any order
  d = decide_percentile_stop(r, v);
  CHECK(d.state == StopState::met);
  CHECK(d.bound_rank == 2218);
  CHECK(d.estimate == Approx(1.0 + 2217.0 * 0.99865).epsilon(1e-14));
  CHECK(d.hi == 2218.0);
  CHECK(d.achieved == Approx((2218.0 - (1.0 + 2217.0 * 0.99865)) / (1.0 + 2217.0 * 0.99865)).epsilon(1e-12));
  // A target of 1e-4: 2218 (13.51)^2 runs, held to 4 n: 6654 more.
  r.width = 1e-4;
  d = decide_percentile_stop(r, v);
  CHECK(d.state == StopState::more);
  CHECK(d.next_runs == 3 * 2218);
  r.max_runs = 2218;
  CHECK(decide_percentile_stop(r, v).state == StopState::capped);
}
