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
  const Allowable a = find_allowable_on_side(x, log_linear(x, [](double v) { return -(v + 3.0); }), +1, 1e-6);
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
  const Allowable a = find_allowable_on_side(x, log_linear(x, [](double v) { return v - 8.0; }), -1, 1e-6);
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
  const Allowable none_safe = find_allowable_on_side(x, b, +1, 1e-8);
  CHECK(none_safe.status == AllowableStatus::beyond_safe_end);
  CHECK_THAT(none_safe.message, Contains("extend the sweep above 4"));
  CHECK(std::isnan(none_safe.value));
  const Allowable all_safe = find_allowable_on_side(x, b, +1, 1e-3);
  CHECK(all_safe.status == AllowableStatus::beyond_unsafe_end);
  CHECK_THAT(all_safe.message, Contains("extend it below 1"));
  CHECK(std::isnan(all_safe.value));
  // The design variable's unit, when given, follows each value the message names.
  CHECK_THAT(find_allowable_on_side(x, b, +1, 1e-8, "Nm").message, Contains("at 4 Nm,") && Contains("extend the sweep above 4 Nm"));
  CHECK_THAT(find_allowable_on_side(x, b, +1, 1e-3, "Nm").message, Contains("extend it below 1 Nm"));
}

TEST_CASE("the first crossing from the safe end, unusable values skipped", "[allowable]") {
  const std::vector<double> x = {1, 2, 3, 4, 5};
  std::vector<ProbabilityBounds> b = log_linear(x, [](double v) { return -(v + 3.0); });
  b[4] = ProbabilityBounds{};  // no estimate at x = 5: the safe end is x = 4
  b[1] = bounds(1e-8, 2e-8, 1e-9, 3e-8);  // a dip below the target on the unsafe side does not count
  const Allowable a = find_allowable_on_side(x, b, +1, 1e-6);
  REQUIRE(a.status == AllowableStatus::found);
  CHECK(a.value == Approx(3.0 + std::log10(2.0)).epsilon(1e-12));
  // A zero lower bound (Monte Carlo without a failure) puts that end of the interval at the next value.
  b = log_linear(x, [](double v) { return -(v + 3.0); });
  b[3] = bounds(0.0, 2e-7, 0.0, 3e-7);
  b[2] = bounds(1e-6, 2e-6, 0.0, 3e-6);
  const Allowable z = find_allowable_on_side(x, b, +1, 1e-6);
  CHECK(z.lower == Approx(2.0).epsilon(1e-12));  // lo(2) = 1e-5 / 3 > T; lo(3) = 0: the crossing at x = 2
  CHECK(find_allowable_on_side({1, 2}, {ProbabilityBounds{}, b[2]}, +1, 1e-6).status == AllowableStatus::unusable);
}

TEST_CASE("the declared side decides; a wrong one is said by where the walk ends", "[allowable]") {
  // p falls as x grows (10^-(x+3)); read on the wrong side (below), the walk starts at x = 1, whose
  // upper bound 2e-4 exceeds the target: beyond the safe end, extend below 1. Only the declared side
  // tells; monotone_fit.hpp refuses a side the data contradict.
  const std::vector<double> x = {1, 2, 3, 4};
  const Allowable a = find_allowable_on_side(x, log_linear(x, [](double v) { return -(v + 3.0); }), -1, 1e-6);
  CHECK(a.safe_side == -1);
  CHECK(a.status == AllowableStatus::beyond_safe_end);
  CHECK_THAT(a.message, Contains("extend the sweep below 1"));
  CHECK_THROWS_AS(find_allowable_on_side(x, log_linear(x, [](double v) { return -v; }), 0, 1e-6),
                  std::invalid_argument);
}
