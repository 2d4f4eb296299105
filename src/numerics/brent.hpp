// Brent's method (golden section with parabolic steps) for the maximum of a scalar function on
// an interval (Brent 1973, ch. 5; as in Numerical Recipes' `brent`, negated for a maximum).
// Pure: standard library only.
#pragma once
#include <cmath>
#include <utility>

namespace truss::numerics {

// Returns (argmax, max) of f on [a, b] to an abscissa tolerance xtol + 1e-12 |x|.
template <class F>
std::pair<double, double> maximize_brent(F&& f, double a, double b, double xtol) {
  const double cgold = 0.3819660112501051;
  double x = a + cgold * (b - a), w = x, v = x;
  double fx = -f(x), fw = fx, fv = fx;
  double d = 0.0, e = 0.0;
  for (int it = 0; it < 100; ++it) {
    const double xm = 0.5 * (a + b);
    const double tol1 = xtol + 1e-12 * std::abs(x), tol2 = 2.0 * tol1;
    if (std::abs(x - xm) <= tol2 - 0.5 * (b - a)) break;
    bool golden = true;
    if (std::abs(e) > tol1) {
      const double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::abs(q);
      const double etemp = e;
      e = d;
      if (!(std::abs(p) >= std::abs(0.5 * q * etemp) || p <= q * (a - x) || p >= q * (b - x))) {
        d = p / q;
        const double u = x + d;
        if (u - a < tol2 || b - u < tol2) d = (xm - x) >= 0 ? tol1 : -tol1;
        golden = false;
      }
    }
    if (golden) {
      e = (x >= xm) ? a - x : b - x;
      d = cgold * e;
    }
    const double u = std::abs(d) >= tol1 ? x + d : x + (d >= 0 ? tol1 : -tol1);
    const double fu = -f(u);
    if (fu <= fx) {
      if (u >= x) a = x; else b = x;
      v = w; fv = fw; w = x; fw = fx; x = u; fx = fu;
    } else {
      if (u < x) a = u; else b = u;
      if (fu <= fw || w == x) { v = w; fv = fw; w = u; fw = fu; }
      else if (fu <= fv || v == x || v == w) { v = u; fv = fu; }
    }
  }
  return {x, -fx};
}

}  // namespace truss::numerics
