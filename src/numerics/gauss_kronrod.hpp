// Adaptive Gauss-Kronrod (7, 15) quadrature (Piessens et al., QUADPACK's qk15 nodes and weights),
// bisecting until |K15 - G7| <= abs_tol on each piece (the tolerance halves with each split).
// A piece whose estimate is not finite is not split (a NaN error estimate never passes the
// tolerance test and would otherwise bisect to the depth cap, 2^30 pieces): its non-finite K15
// is returned and propagates to the caller, whose checks name the run's failure. Depth cap 30
// for finite integrands as before.
// Pure: standard library only.
#pragma once
#include <cmath>

namespace truss::numerics {

template <class F>
double integrate_gk15(F&& f, double a, double b, double abs_tol, int depth = 0) {
  static constexpr double xgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                    0.207784955007898467600689403773245, 0.0};
  static constexpr double wgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
  static constexpr double wg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                   0.381830050505118944950369775488975, 0.417959183673469387755102040816327};
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  const double fc = f(c);
  double k = wgk[7] * fc, g = wg[3] * fc;
  for (int j = 0; j < 7; ++j) {
    const double f1 = f(c - h * xgk[j]), f2 = f(c + h * xgk[j]);
    k += wgk[j] * (f1 + f2);
    if (j % 2 == 1) g += wg[j / 2] * (f1 + f2);
  }
  k *= h; g *= h;
  if (!std::isfinite(k) || !std::isfinite(g)) return k;
  if (std::abs(k - g) <= abs_tol || depth >= 30) return k;
  return integrate_gk15(f, a, c, 0.5 * abs_tol, depth + 1) + integrate_gk15(f, c, b, 0.5 * abs_tol, depth + 1);
}

}  // namespace truss::numerics
