// Static resistance of the free stack (docs/model-notes.md "Resistive torque"): the drive force F
// (N, along +y) that holds the stack at rest with the deploying bay m in a given configuration, every
// free frame below it in static equilibrium, from the diagonals' potential V = sum_i U_i(D_i)
// (docs/model.md §1; the model's only potential: no gravity in orbit, the rail and the stack
// contacts are constraints). At rest the generalized force of V on every free frame vanishes:
// U_i'(D_i) = U_{i+1}'(D_{i+1}) for the bays below the driven frame, so the bays between a held
// frame and the first frame the drive or the rail positions pull with one tension, the chain's.
//   Off the rail (phase A), the configuration of the deploying bay is its opening D_m; the driven
//     frame's equilibrium is F = U_m'(D_m), the bays below carry the same pull whatever their
//     heights (a lower bay that would have to open past straight holds as a rigid member).
//   On the rail (phase B), its configuration is the hinge offset x, which places the driven frame
//     at Y(x) and the lower frame m-1 at Z(x) (model/rail.hpp); bays 1..m-1 span Z - y_0 above the
//     floor's frame 0 with the chain tension P(Z - y_0) (P = 0 while they can all be slack), so
//     the stack's potential at rest is V(x) = U_m(D(x)) + V_chain(Z(x)), dV_chain/dZ = P, and by
//     virtual work along the rail (F dY = dV):
//       F = (U_m'(D) D'(x) + P Z'(x)) / Y'(x),  D = 2 s,  D' = -2 x / s,  s = sqrt(l^2 - x^2).
//     With a single bay below (m = 2) this is the held stack's on-rail static force (stages/
//     held_phase.cpp, -(Q_m + Q_l) + k Q_l / gamma) with the same lower bay; with none (m = 1)
//     frame 0 rides the rail and P = 0.
// The chain tension P solves sum_i D_i(P) = span, D_i(P) the opening at which bay i pulls P (the
// inverse of U_i' on [max(D_taut,i, 0), 2 l_i], where U_i' rises: U_i'' = 6 K (D^2 / L^2 +
// (L - l_0) b^2 / L^3) > 0 for a taut bay; 2 l_i once P exceeds the bay's pull at straight).
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "model/bay.hpp"
#include "model/params.hpp"

namespace truss::model {

// Off the rail: F = U_m'(D_m), the pull of the deploying bay's diagonals (N), which the frame
// system already holds as minus the spring force on the driven frame (model/frames.hpp).
inline double calc_open_static_drive_force_N(double bay_pull_N) { return bay_pull_N; }

// On the rail: bay m pulling U_m'(D) = bay_pull_N at the hinge offset with x / s = x_over_s, the
// chain below pulling P = chain_pull_N; D' = -2 x / s, Z' = -c + x / s, Y' = -c - x / s.
inline double calc_on_rail_static_drive_force_N(double cot_beta, double x_over_s, double bay_pull_N, double chain_pull_N) {
  return (bay_pull_N * (-2.0 * x_over_s) + chain_pull_N * (x_over_s - cot_beta)) / (-cot_beta - x_over_s);
}

// d^2U/dD^2 of a bay (N/m): 0 while slack.
inline double calc_bay_d2U_dD2_N_per_m(const BayParams& b, double offset_sq_m2, double D) {
  const double L = calc_diagonal_length_m(offset_sq_m2, D), stretch = L - b.diagonal_free_length_m;
  if (!(stretch > 0.0)) return 0.0;
  return 6.0 * b.diagonal_stiffness_N_per_m * (D * D / (L * L) + stretch * offset_sq_m2 / (L * L * L));
}

// The opening (m) at which bay b's diagonals pull with dU/dD = pull_N (>= 0): Newton's method from
// guess_m (or straight) kept inside a shrinking bracket (bisection where a step leaves it), to the
// rounding of D.
inline double calc_bay_opening_at_pull_m(const BayParams& b, double offset_sq_m2, double pull_N, double guess_m = 1e300) {
  const double taut = std::max(calc_taut_opening_m(b, offset_sq_m2), 0.0), straight = 2.0 * b.strut_length_m;
  if (!(pull_N > 0.0)) return taut;
  if (!(calc_bay_dU_dD_N(b, offset_sq_m2, straight) > pull_N)) return straight;
  const double tol = 4.0 * std::numeric_limits<double>::epsilon() * straight;
  double lo = taut, hi = straight, D = guess_m > taut && guess_m < straight ? guess_m : straight;
  for (int it = 0; it < 100 && hi - lo > tol; ++it) {
    const double g = calc_bay_dU_dD_N(b, offset_sq_m2, D) - pull_N;
    if (g == 0.0) return D;
    if (g > 0.0) hi = D; else lo = D;
    const double slope = calc_bay_d2U_dD2_N_per_m(b, offset_sq_m2, D);
    const double newton = slope > 0.0 ? D - g / slope : lo;
    const double next = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
    if (std::abs(next - D) <= tol) return next;
    D = next;
  }
  return D;
}

// The slack length of bays first..last in series (m): the largest span over which all of them can
// be slack at once, sum of max(D_taut,i, 0).
inline double calc_chain_slack_span_m(const MastParams& mast, int first_bay, int last_bay) {
  double span = 0.0;
  for (int i = first_bay; i <= last_bay; ++i)
    span += std::max(calc_taut_opening_m(mast.bay(i), calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i))), 0.0);
  return span;
}

// The equilibrium pull P (N) of bays first..last in series spanning span_m (frame first-1 held, frame
// last placed): 0 when span_m <= slack_span_m (calc_chain_slack_span_m), else the root of
// sum_i D_i(P) = span_m, increasing in P, by Newton's method (d span / dP = sum 1 / U_i''(D_i)) kept
// inside a shrinking bracket, to the rounding of P; at a span that needs every bay straight, the
// largest pull of a bay at straight (the smallest pull that holds it there; continuous in the span).
// It starts from the mean pull at equal openings (the root itself when the bays are equal), each
// bay's opening from that opening. A single bay pulls U'(span) directly.
inline double calc_chain_pull_N(const MastParams& mast, int first_bay, int last_bay, double span_m, double slack_span_m) {
  if (!(span_m > slack_span_m) || last_bay < first_bay) return 0.0;
  const int count = last_bay - first_bay + 1;
  const double even = span_m / count;
  double lo = 0.0, hi = 0.0, straight = 0.0, P = 0.0;
  for (int i = first_bay; i <= last_bay; ++i) {
    const BayParams& b = mast.bay(i);
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    straight += 2.0 * b.strut_length_m;
    hi = std::max(hi, calc_bay_dU_dD_N(b, b2, 2.0 * b.strut_length_m));
    P += calc_bay_dU_dD_N(b, b2, std::min(even, 2.0 * b.strut_length_m)) / count;
  }
  if (!(span_m < straight)) return hi;
  if (count == 1) return P;
  const double tol = 4.0 * std::numeric_limits<double>::epsilon() * hi;
  if (!(P > lo && P < hi)) P = 0.5 * hi;
  for (int it = 0; it < 200 && hi - lo > tol; ++it) {
    double g = -span_m, compliance = 0.0;
    for (int i = first_bay; i <= last_bay; ++i) {
      const BayParams& b = mast.bay(i);
      const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
      const double D = calc_bay_opening_at_pull_m(b, b2, P, even);
      g += D;
      const double stiff = calc_bay_d2U_dD2_N_per_m(b, b2, D);
      if (stiff > 0.0 && D < 2.0 * b.strut_length_m) compliance += 1.0 / stiff;
    }
    if (g == 0.0) return P;
    if (g > 0.0) hi = P; else lo = P;
    const double newton = compliance > 0.0 ? P - g / compliance : lo;
    const double next = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
    if (std::abs(next - P) <= tol) return next;
    P = next;
  }
  return P;
}

}  // namespace truss::model
