// Adaptive Gauss-Kronrod (numerics/gauss_kronrod.hpp): exact for polynomials up to degree 22 on
// one piece, and bounded work when the integrand is not finite (a NaN error estimate must not
// bisect to depth 30, about 1e9 evaluations).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "numerics/gauss_kronrod.hpp"

using truss::numerics::integrate_gk15;

namespace {
// Counts evaluations and throws past a budget, so that a regression fails instead of hanging.
struct Counted {
  long calls = 0;
  long budget = 100000;
  double operator()(double x, double (*f)(double)) {
    if (++calls > budget) throw std::runtime_error("evaluation budget exceeded");
    return f(x);
  }
};
}  // namespace

TEST_CASE("GK15: polynomial and smooth integrands", "[numeric][quadrature]") {
  // int_0^2 x^5 dx = 64 / 6: K15 is exact for degree <= 22, so one piece (15 calls), error at
  // the rounding level of the 15-term sum (a few ulps of 10.7).
  Counted c;
  const double v = integrate_gk15([&](double x) { return c(x, [](double t) { return t * t * t * t * t; }); }, 0.0, 2.0, 1e-12);
  CHECK(v == Catch::Detail::Approx(64.0 / 6.0).epsilon(1e-14));
  CHECK(c.calls == 15);
  // int_0^pi sin = 2 (analytic), tolerance 1e-12 absolute as requested.
  CHECK(std::abs(integrate_gk15([](double x) { return std::sin(x); }, 0.0, M_PI, 1e-12) - 2.0) < 1e-12);
}

TEST_CASE("GK15: a NaN integrand ends after one piece and returns NaN", "[numeric][quadrature]") {
  Counted c;
  double v = 0;
  REQUIRE_NOTHROW(v = integrate_gk15([&](double x) { return c(x, [](double) { return std::numeric_limits<double>::quiet_NaN(); }); },
                                     0.0, 1.0, 1e-12));
  CHECK(std::isnan(v));
  CHECK(c.calls == 15);  // the first piece's 15 nodes, no bisection
}

TEST_CASE("GK15: NaN on part of the interval propagates; a finite kink still bisects", "[numeric][quadrature]") {
  // f = x on [0, 0.7), NaN beyond: nodes of the first piece lie beyond 0.7, so it stops there.
  Counted c;
  double v = 0;
  REQUIRE_NOTHROW(v = integrate_gk15([&](double x) { return c(x, [](double t) { return t < 0.7 ? t : std::nan(""); }); },
                                     0.0, 1.0, 1e-10));
  CHECK(std::isnan(v));
  CHECK(c.calls == 15);
  // int_0^1 |x - 1/3| dx = (1/3)^2 / 2 + (2/3)^2 / 2 = 5/18: the kink needs bisection (more than
  // one piece) and the result meets the requested 1e-10 (the per-piece tolerances sum to it).
  Counted k;
  const double w = integrate_gk15([&](double x) { return k(x, [](double t) { return std::abs(t - 1.0 / 3.0); }); }, 0.0, 1.0, 1e-10);
  CHECK(std::abs(w - 5.0 / 18.0) < 1e-10);
  CHECK(k.calls > 15);
}

TEST_CASE("GK15: an infinite integrand ends at once", "[numeric][quadrature]") {
  Counted c;
  double v = 0;
  REQUIRE_NOTHROW(v = integrate_gk15([&](double x) { return c(x, [](double t) { return 1e308 * 1e308 * t; }); }, 0.5, 1.0, 1e-10));
  CHECK(std::isinf(v));
  CHECK(c.calls == 15);
}
