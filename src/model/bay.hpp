// One bay of the mast as pure functions of its opening D = y_i - y_{i-1} (docs/model.md §1, 3).
//
// Kinetic energy of bay i (paper eq. 1, docs/model.md §3), u = dy_i/dt, w = dy_{i-1}/dt:
//   T_i = G(D) (u - w)^2 + (3/32) m_s (10 u^2 + 12 u w + 10 w^2) + (1/2) m_f,i u^2
//   G(D)  = (3/16 m_s D^2 + 3 J_c) / (4 l_s^2 - D^2)
//   G'(D) = D (3/2 m_s l_s^2 + 6 J_c) / (4 l_s^2 - D^2)^2   (docs/model.md §3.1 (1): not 2 m_s l_s^2)
// Hinge offset x = (1/2) sqrt(4 l_s^2 - D^2) (paper eq. 18). Near the lock G blows up like 1/x^2,
// but G dD/dt^2 is regular in x: with s = sqrt(l_s^2 - x^2), D = 2 s, dD/dt = -(2x/s) dx/dt,
//   G (dD/dt)^2 = g(x) (dx/dt)^2,   g(x) = 3/4 m_s + 3 J_c / s^2,   g'(x) = 6 J_c x / s^4,
// and g(0) (dx/dt)^2 is the latch energy of docs/model.md §2.
// Diagonals (docs/model.md §1): six per bay, tension only, length L = sqrt(b^2 + D^2) with
//   b^2 = (b_lo^2 + b_lo b_up + b_up^2) / 3,
// the horizontal distance between a vertex of the lower frame and the next vertex of the upper
// frame (exactly b_f^2 when both frames have side b_f; the project's reading for frames of
// different sides, docs/model-notes.md). U = 3 K (L - l_0)^2 when L > l_0, else 0.
#pragma once
#include <algorithm>
#include <cmath>

#include "model/params.hpp"

namespace truss::model {

// Mass-matrix constants of one bay (docs/model.md §3): its regular part on the upper and lower frame
// and their coupling; a locked bay moves rigidly with 6 m_s + m_f.
inline double calc_regular_upper_mass_kg(const BayParams& b) { return 15.0 / 8.0 * b.strut_mass_kg; }
inline double calc_regular_lower_mass_kg(const BayParams& b) { return 15.0 / 8.0 * b.strut_mass_kg; }
inline double calc_regular_coupling_mass_kg(const BayParams& b) { return 9.0 / 8.0 * b.strut_mass_kg; }
inline double calc_rigid_bay_mass_kg(const BayParams& b, const FrameParams& upper) {
  return 6.0 * b.strut_mass_kg + upper.mass_kg;
}

// The functions of D are templates on the number type (double, or a dual number that carries a
// time derivative through the closed forms); the same expressions, so the same bits in double.
// Each law is written once, on the constants of the bay it needs (StrutConstants,
// DiagonalConstants); the overloads on BayParams compute those constants first. A caller that
// evaluates a law often computes its constants once (model/frames.hpp, BayConstants): the same
// products in the same order, so the same bits either way.

// Constants of G and G' (above): G = (G_quadratic D^2 + G_constant) / (4 l_s^2 - D^2),
// G' = D G'_numerator / (4 l_s^2 - D^2)^2.
struct StrutConstants {
  double G_quadratic_kg = 0;        // 3/16 m_s
  double G_constant_kg_m2 = 0;      // 3 J_c
  double four_l2_m2 = 0;            // 4 l_s^2
  double dG_numerator_kg_m2 = 0;    // 3/2 m_s l_s^2 + 6 J_c
};

inline StrutConstants calc_strut_constants(const BayParams& b) {
  const double l = b.strut_length_m;
  return {3.0 / 16.0 * b.strut_mass_kg, 3.0 * b.strut_inertia_kg_m2, 4.0 * l * l,
          1.5 * b.strut_mass_kg * l * l + 6.0 * b.strut_inertia_kg_m2};
}

template <class T>
T calc_G(const StrutConstants& c, T D) {
  return (c.G_quadratic_kg * D * D + c.G_constant_kg_m2) / (c.four_l2_m2 - D * D);
}

template <class T>
T calc_dG_dD(const StrutConstants& c, T D) {
  const T den = c.four_l2_m2 - D * D;
  return D * c.dG_numerator_kg_m2 / (den * den);
}

template <class T>
T calc_G(const BayParams& b, T D) { return calc_G(calc_strut_constants(b), D); }

template <class T>
T calc_dG_dD(const BayParams& b, T D) { return calc_dG_dD(calc_strut_constants(b), D); }

// g(x): coefficient of (dx/dt)^2 in the strut kinetic energy, regular at the lock x = 0.
template <class T>
T calc_g_hinge(const BayParams& b, T x) {
  const T s2 = b.strut_length_m * b.strut_length_m - x * x;
  return 0.75 * b.strut_mass_kg + 3.0 * b.strut_inertia_kg_m2 / s2;
}

template <class T>
T calc_dg_hinge_dx(const BayParams& b, T x) {
  const T s2 = b.strut_length_m * b.strut_length_m - x * x;
  return 6.0 * b.strut_inertia_kg_m2 * x / (s2 * s2);
}

// Latch energy per unit (dx/dt)^2 at the lock: (3/4 m_s + 3 J_c / l_s^2).
inline double calc_latch_energy_J(const BayParams& b, double hinge_speed_m_per_s) {
  return calc_g_hinge(b, 0.0) * hinge_speed_m_per_s * hinge_speed_m_per_s;
}

template <class T>
T calc_hinge_offset_m(const BayParams& b, T D) {
  using std::sqrt;
  const double l = b.strut_length_m;
  const T q = 4.0 * l * l - D * D;
  return 0.5 * sqrt(0.0 < q ? q : T(0.0));  // std::max(0.0, q)
}

inline double calc_diagonal_offset_sq_m2(const FrameParams& lower, const FrameParams& upper) {
  return (lower.side_m * lower.side_m + lower.side_m * upper.side_m + upper.side_m * upper.side_m) / 3.0;
}

template <class T>
T calc_diagonal_length_m(double offset_sq_m2, T D) {
  using std::sqrt;
  return sqrt(offset_sq_m2 + D * D);
}

// Constants of the diagonals' laws below. slack_opening_sq_m2: a D^2 at or below which the
// computed stretch sqrt(b^2 + D^2) - l_0 is not positive (calc_slack_opening_sq_m2), so that the
// laws are their exact zero without the square root; -1: none known (every D computes the stretch).
struct DiagonalConstants {
  double offset_sq_m2 = 0;          // b^2
  double free_length_m = 0;         // l_0
  double stiffness_N_per_m = 0;     // K of one diagonal
  double slack_opening_sq_m2 = -1;  // see above
  // True if the diagonals are slack at D (D2 = D * D) by the bound alone.
  template <class T>
  bool is_surely_slack(T D2) const { return D2 <= slack_opening_sq_m2; }
};

// The largest D^2 (less a relative 1e-9, so that the check passes at once) at which the computed
// stretch is not positive: every operation of the stretch, D^2 -> b^2 + D^2 -> sqrt -> - l_0,
// rounds monotonically, so any D^2 at or below one that gives sqrt(b^2 + D^2) <= l_0 gives a stretch
// <= 0 as well. -1 when the diagonals are taut at D = 0 (or the check fails: no bound).
inline double calc_slack_opening_sq_m2(double offset_sq_m2, double free_length_m) {
  double t = (free_length_m * free_length_m - offset_sq_m2) * (1.0 - 1e-9);
  for (int i = 0; i < 4 && t > 0.0; ++i, t *= 0.5)
    if (std::sqrt(offset_sq_m2 + t) <= free_length_m) return t;
  return -1.0;
}

inline DiagonalConstants calc_diagonal_constants(const BayParams& b, double offset_sq_m2) {
  return {offset_sq_m2, b.diagonal_free_length_m, b.diagonal_stiffness_N_per_m, -1.0};
}

// Tension in one diagonal (N); zero when slack.
template <class T>
T calc_diagonal_tension_N(const DiagonalConstants& c, T D) {
  using std::sqrt;
  const T D2 = D * D;
  if (c.is_surely_slack(D2)) return T(0.0);
  const T stretch = sqrt(c.offset_sq_m2 + D2) - c.free_length_m;
  return stretch > 0.0 ? c.stiffness_N_per_m * stretch : T(0.0);
}

// Potential of the six diagonals of the bay (J).
template <class T>
T calc_bay_potential_J(const DiagonalConstants& c, T D) {
  using std::sqrt;
  const T D2 = D * D;
  if (c.is_surely_slack(D2)) return T(0.0);
  const T stretch = sqrt(c.offset_sq_m2 + D2) - c.free_length_m;
  return stretch > 0.0 ? 3.0 * c.stiffness_N_per_m * stretch * stretch : T(0.0);
}

// dU/dD of the bay (N): the force with which the diagonals pull the two frames together.
template <class T>
T calc_bay_dU_dD_N(const DiagonalConstants& c, T D) {
  using std::sqrt;
  const T D2 = D * D;
  if (c.is_surely_slack(D2)) return T(0.0);
  const T L = sqrt(c.offset_sq_m2 + D2);
  const T stretch = L - c.free_length_m;
  return stretch > 0.0 ? 6.0 * c.stiffness_N_per_m * stretch * D / L : T(0.0);
}

template <class T>
T calc_diagonal_tension_N(const BayParams& b, double offset_sq_m2, T D) {
  return calc_diagonal_tension_N(calc_diagonal_constants(b, offset_sq_m2), D);
}

template <class T>
T calc_bay_potential_J(const BayParams& b, double offset_sq_m2, T D) {
  return calc_bay_potential_J(calc_diagonal_constants(b, offset_sq_m2), D);
}

template <class T>
T calc_bay_dU_dD_N(const BayParams& b, double offset_sq_m2, T D) {
  return calc_bay_dU_dD_N(calc_diagonal_constants(b, offset_sq_m2), D);
}

// Opening at which the diagonals become taut (a kink of the forces); negative if taut at D = 0.
inline double calc_taut_opening_m(const BayParams& b, double offset_sq_m2) {
  const double l0 = b.diagonal_free_length_m;
  const double d2 = l0 * l0 - offset_sq_m2;
  return d2 > 0.0 ? std::sqrt(d2) : -1.0;
}

}  // namespace truss::model
