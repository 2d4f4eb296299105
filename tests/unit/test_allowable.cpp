// test_allowable.cpp — a sweep's allowable (src/sampling/allowable.hpp). The bounds against scipy
// 1.10.1 (norm.ppf, beta.ppf; 1e-10 relative: both invert to a few ulps, and a wrong tail or
// quantile moves them by percents); the crossing on estimates that are exactly log-linear in the
// design value, where linear interpolation in ln p is exact and the crossing has a closed form:
// p = 10^-(x + 3), bounds 2p (one-sided), p / 3 and 3p (interval), target 1e-6:
// allowable 3 + log10 2, estimate 3, interval [3 - log10 3, 3 + log10 3] (to rounding: 1e-12).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "sampling/allowable.hpp"

using namespace truss::sampling;
using Catch::Matchers::Contains;

namespace {

ProbabilityBounds bounds(double p, double ub, double lo, double hi) {
  ProbabilityBounds b;
  b.p = p;
  b.upper_bound = ub;
  b.lower = lo;
  b.upper = hi;
  return b;
}

// p = 10^e(x) at each x, with the bounds above.
std::vector<ProbabilityBounds> log_linear(const std::vector<double>& x, double (*e)(double)) {
  std::vector<ProbabilityBounds> b;
  for (double v : x) {
    const double p = std::pow(10.0, e(v));
    b.push_back(bounds(p, 2.0 * p, p / 3.0, 3.0 * p));
  }
  return b;
}

}  // namespace

TEST_CASE("lognormal and binomial bounds match scipy", "[allowable]") {
  const ProbabilityBounds s = calc_lognormal_bounds(1e-6, 0.3, 0.95);
  CHECK(s.upper_bound == Approx(1.6207092376734722e-06).epsilon(1e-10));
  CHECK(s.lower == Approx(5.624979605850976e-07).epsilon(1e-10));
  CHECK(s.upper == Approx(1.7777842233593571e-06).epsilon(1e-10));
  CHECK_FALSE(calc_lognormal_bounds(0.0, 0.3, 0.95).usable());  // no failing sample: no bound
  const ProbabilityBounds b = calc_binomial_bounds(3, 1000, 0.95);
  CHECK(b.p == 0.003);
  CHECK(b.upper_bound == Approx(0.007735244718479458).epsilon(1e-10));
  CHECK(b.lower == Approx(0.0006190999316495713).epsilon(1e-10));
  CHECK(b.upper == Approx(0.008742023238478303).epsilon(1e-10));
  CHECK(calc_binomial_bounds(0, 1000, 0.95).upper_bound == Approx(0.0029912495450953314).epsilon(1e-10));
}

TEST_CASE("the allowable where p falls with the design value", "[allowable]") {
  const std::vector<double> x = {1, 2, 3, 4};
  const Allowable a = find_allowable(x, log_linear(x, [](double v) { return -(v + 3.0); }), 1e-6);
  REQUIRE(a.status == AllowableStatus::found);
  CHECK(a.safe_side == +1);
  CHECK(a.value == Approx(3.0 + std::log10(2.0)).epsilon(1e-12));
  CHECK(a.estimate == Approx(3.0).epsilon(1e-12));
  CHECK(a.lower == Approx(3.0 - std::log10(3.0)).epsilon(1e-12));
  CHECK(a.upper == Approx(3.0 + std::log10(3.0)).epsilon(1e-12));
  CHECK(a.bracket_safe == 3);
  CHECK(a.bracket_unsafe == 2);
}

TEST_CASE("the allowable where p grows with the design value (a tolerance)", "[allowable]") {
  const std::vector<double> x = {1, 2, 3, 4};
  const Allowable a = find_allowable(x, log_linear(x, [](double v) { return v - 8.0; }), 1e-6);
  REQUIRE(a.status == AllowableStatus::found);
  CHECK(a.safe_side == -1);
  CHECK(a.value == Approx(2.0 - std::log10(2.0)).epsilon(1e-12));
  CHECK(a.estimate == Approx(2.0).epsilon(1e-12));
  CHECK(a.lower == Approx(2.0 - std::log10(3.0)).epsilon(1e-12));
  CHECK(a.upper == Approx(2.0 + std::log10(3.0)).epsilon(1e-12));
}

TEST_CASE("a target outside the swept range is said, with the way to extend", "[allowable]") {
  const std::vector<double> x = {1, 2, 3, 4};
  const auto b = log_linear(x, [](double v) { return -(v + 3.0); });  // 1e-4 .. 1e-7
  const Allowable none_safe = find_allowable(x, b, 1e-8);
  CHECK(none_safe.status == AllowableStatus::beyond_safe_end);
  CHECK_THAT(none_safe.message, Contains("extend the sweep above 4"));
  CHECK(std::isnan(none_safe.value));
  const Allowable all_safe = find_allowable(x, b, 1e-3);
  CHECK(all_safe.status == AllowableStatus::beyond_unsafe_end);
  CHECK_THAT(all_safe.message, Contains("extend it below 1"));
  CHECK(std::isnan(all_safe.value));
  // The design variable's unit, when given, follows each value the message names.
  CHECK_THAT(find_allowable(x, b, 1e-8, "Nm").message, Contains("at 4 Nm,") && Contains("extend the sweep above 4 Nm"));
  CHECK_THAT(find_allowable(x, b, 1e-3, "Nm").message, Contains("extend it below 1 Nm"));
}

TEST_CASE("the first crossing from the safe end, unusable values skipped", "[allowable]") {
  const std::vector<double> x = {1, 2, 3, 4, 5};
  std::vector<ProbabilityBounds> b = log_linear(x, [](double v) { return -(v + 3.0); });
  b[4] = ProbabilityBounds{};  // no estimate at x = 5: the safe end is x = 4
  b[1] = bounds(1e-8, 2e-8, 1e-9, 3e-8);  // a dip below the target on the unsafe side does not count
  const Allowable a = find_allowable(x, b, 1e-6);
  REQUIRE(a.status == AllowableStatus::found);
  CHECK(a.value == Approx(3.0 + std::log10(2.0)).epsilon(1e-12));
  // A zero lower bound (Monte Carlo without a failure) puts that end of the interval at the next value.
  b = log_linear(x, [](double v) { return -(v + 3.0); });
  b[3] = bounds(0.0, 2e-7, 0.0, 3e-7);
  b[2] = bounds(1e-6, 2e-6, 0.0, 3e-6);
  const Allowable z = find_allowable(x, b, 1e-6);
  CHECK(z.lower == Approx(2.0).epsilon(1e-12));  // lo(2) = 1e-5 / 3 > T; lo(3) = 0: the crossing at x = 2
  CHECK(find_allowable({1, 2}, {ProbabilityBounds{}, b[2]}, 1e-6).status == AllowableStatus::unusable);
}

TEST_CASE("no failure at either end: the runs' nearest approach to failure gives the safe side", "[allowable]") {
  // Monte Carlo without a failure at any value (1000 runs each): every bound the same, so p does
  // not say which way it falls. The smallest margins do: a stall torque's margin grows with the
  // value (the safe side above: extend below the smallest value), a tolerance's shrinks.
  const std::vector<double> x = {12, 13, 14, 15};
  const std::vector<ProbabilityBounds> b(4, calc_binomial_bounds(0, 1000, 0.95));  // upper bound 2.99e-3
  const NearestMargins growing{{1e-4, 2e-4, 3e-4, 4e-4}, "Nm"}, shrinking{{4e-4, 3e-4, 2e-4, 1e-4}, "Nm"};
  const Allowable up = find_allowable(x, b, 1e-2, "mNm", growing);
  CHECK(up.status == AllowableStatus::beyond_unsafe_end);
  CHECK(up.safe_side == +1);
  CHECK_THAT(up.message, Contains("extend it below 12 mNm") && Contains("the runs at 12 mNm came nearer to failure")
                             && Contains("smallest margin 0.0001 Nm against 0.0004 Nm at 15 mNm"));
  const Allowable down = find_allowable(x, b, 1e-2, "mNm", shrinking);
  CHECK(down.safe_side == -1);
  CHECK_THAT(down.message, Contains("extend it above 15 mNm"));
  // Every bound above the target: beyond the safe end, which the margins name.
  const Allowable none_safe = find_allowable(x, b, 1e-4, "mNm", growing);
  CHECK(none_safe.status == AllowableStatus::beyond_safe_end);
  CHECK_THAT(none_safe.message, Contains("extend the sweep above 15 mNm"));
  // Only the ends of the values with bounds count (value 15 has none here).
  std::vector<ProbabilityBounds> b3 = b;
  b3[3] = ProbabilityBounds{};
  CHECK(find_allowable(x, b3, 1e-2, "", {{1e-4, 2e-4, 3e-4, 0.0}, ""}).safe_side == +1);
}

TEST_CASE("no failure at either end and nothing else tells: the direction is unknown", "[allowable]") {
  const std::vector<double> x = {12, 13, 14, 15};
  const std::vector<ProbabilityBounds> b(4, calc_binomial_bounds(0, 1000, 0.95));
  const double nan = std::nan("");
  for (const NearestMargins& m : {NearestMargins{}, NearestMargins{{nan, 2e-4, 3e-4, nan}, "Nm"},
                                  NearestMargins{{1e-4, 2e-4, 3e-4, 1e-4}, "Nm"}}) {
    const Allowable a = find_allowable(x, b, 1e-2, "mNm", m);
    CHECK(a.status == AllowableStatus::direction_unknown);
    CHECK(a.safe_side == 0);
    CHECK(std::isnan(a.value));
    CHECK_THAT(a.message, Contains("every value's upper bound on p is at or below the target")
                              && Contains("the direction in which p falls is unknown") && !Contains("extend"));
  }
  CHECK_THAT(find_allowable(x, b, 1e-4, "mNm").message, Contains("no value's upper bound on p is at or below"));
  // Equal estimates at the ends with failures in the middle: the bounds cross the target, but from
  // which end is unknown.
  std::vector<ProbabilityBounds> mid = b;
  mid[1] = calc_binomial_bounds(30, 1000, 0.95);
  CHECK_THAT(find_allowable(x, mid, 1e-2).message, Contains("the upper bounds on p cross the target"));
  // With different estimates at the ends the estimates decide, whatever the margins say.
  std::vector<ProbabilityBounds> falling = b;
  falling[0] = calc_binomial_bounds(5, 1000, 0.95);
  CHECK(find_allowable(x, falling, 1e-2, "", {{4e-4, 3e-4, 2e-4, 1e-4}, ""}).safe_side == +1);
}
