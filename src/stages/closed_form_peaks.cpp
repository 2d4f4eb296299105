#include "stages/closed_form_peaks.hpp"

namespace truss::stages {

HermiteMaximum find_hermite_maximum(const RatedSample& a, const RatedSample& b, int k) {
  HermiteMaximum r;
  const std::size_t ki = static_cast<std::size_t>(k);
  const double h = b.t - a.t;
  const double f0 = a.q[ki], f1 = b.q[ki], m0 = a.dq[ki] * h, m1 = b.dq[ki] * h;
  if (!(h > 0.0) || !std::isfinite(f0) || !std::isfinite(f1) || !std::isfinite(m0) || !std::isfinite(m1)) return r;
  // Slopes and rises below the rounding of the values carry no shape (a prescribed speed's).
  const double noise = 16.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(f0), std::abs(f1));
  if (std::max(std::abs(m0), std::abs(m1)) <= noise) return r;
  // H(s) = h00 f0 + h10 m0 + h01 f1 + h11 m1 on s in [0, 1]; H'(s) = A s^2 + B s + C.
  const double A = 6.0 * (f0 - f1) + 3.0 * (m0 + m1), B = 6.0 * (f1 - f0) - 4.0 * m0 - 2.0 * m1, C = m0;
  double roots[2];
  int nr = 0;
  if (std::abs(A) <= 1e-12 * (std::abs(B) + std::abs(C))) {
    if (B != 0.0) roots[nr++] = -C / B;
  } else {
    const double disc = B * B - 4.0 * A * C;
    if (disc < 0.0) return r;
    const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
    roots[nr++] = q / A;
    if (q != 0.0) roots[nr++] = C / q;
  }
  double s_max = kNaN, s_min = kNaN;
  for (int i = 0; i < nr; ++i) {
    const double s = roots[i];
    if (!(s > 0.0 && s < 1.0)) continue;
    if (2.0 * A * s + B < 0.0) s_max = s;
    else s_min = s;
  }
  if (!std::isfinite(s_max)) return r;
  const double s = s_max, s2 = s * s, s3 = s2 * s;
  r.value = (2.0 * s3 - 3.0 * s2 + 1.0) * f0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * f1 + (s3 - s2) * m1;
  // A maximum between slopes of one sign must rise above the samples by more than their rounding.
  if (!(m0 > 0.0 && m1 < 0.0) && !(r.value > std::max(f0, f1) + noise)) return r;
  r.found = true;
  r.s = s;
  r.s_other = s_min;
  return r;
}

}  // namespace truss::stages
