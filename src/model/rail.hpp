// Guide rail and the hinge on it (paper eqs. 17-18, docs/model.md §1-§3).
//   f(x_h, y_h) = y_h - y_l + cot(beta) (x_h - x_l)          (rail function, eq. 17)
// with c = cot(beta) and y_r = y_l + c x_l (rail height on the longeron line), f = 0 reads
//   y_h = y_r - c x_h.
// A bay of strut length l with the hinge at offset x has its frames at y_h +- s, s = sqrt(l^2 - x^2).
// On the rail the deploying bay is parametrised by x (regular at the lock x = 0, docs/model.md §3):
//   Y(x) = y_r - c x + s   (upper, driven frame)      Y' = -c - x/s,  Y'' = -l^2/s^3
//   Z(x) = y_r - c x - s   (lower frame)              Z' = -c + x/s,  Z'' =  l^2/s^3
// In coordinates (y_m, x) the rail function is f = y_m - s(x) - y_r + c x, with gradient
//   (1, c + x/s): regular at the lock, unlike df/dy in frame heights (docs/model.md §3.1 (4)).
// Rail normal force on one of the three pins: |lambda| / (3 sin beta).
// Rail margin of an entry (free stack, docs/model-notes.md "Rail margin"). The dip: with the hinge at
//   y_h = (y_m + y_lo)/2, x_h = sqrt(l^2 - D^2/4), D = y_m - y_lo,
//   f' = (u + w)/2 + c x',   x' = -D D' / (4 x),
//   f'' = (a_u + a_w)/2 + c x'',   x'' = -(D'^2 + D D'') / (4 x) - x'^2 / x,
// phase A continued through the entry with f'' held is f(tau) = f' tau + f'' tau^2 / 2 (f = 0 at
// the entry), over a horizon T = l / max(|u|, |f'|) (the time the drive takes to move the driven
// frame one strut length): the uncaptured pin would dip to
//   d = max over tau in [0, T] of -(f' tau + f'' tau^2 / 2)
// below the rail (f'^2 / (2 f'') when the minimum falls within T), d sin(beta) from the rail line.
// The margin adds the slack s = l_0 - L(D) the deploying bay's diagonals still have at the entry,
// in series with the dip (s+ = max(s, 0)):
//   margin = d + d s+ / (d + s+)
#pragma once
#include <algorithm>
#include <cmath>

#include "model/params.hpp"

namespace truss::model {

inline double calc_rail_function_m(const RailParams& r, double hinge_x_m, double hinge_y_m) {
  return hinge_y_m - r.y_m + r.cot_beta() * (hinge_x_m - r.x_m);
}

inline double calc_pin_force_N(const RailParams& r, double lambda_N) {
  return std::abs(lambda_N) / (3.0 * std::sin(r.beta_rad));
}

// The rail's trigonometric constants, computed once per phase rather than per evaluation (the
// same expressions, so the same bits): c = cot(beta), y_r, and 3 sin(beta) for the pin force.
struct RailConstants {
  double cot_beta = 0, axis_height_m = 0, three_sin_beta = 0;
};
inline RailConstants calc_rail_constants(const RailParams& r) {
  return {r.cot_beta(), r.axis_height_m(), 3.0 * std::sin(r.beta_rad)};
}
// Templates on the number type below (double, or a dual number carrying a time derivative), as
// model/bay.hpp: the same expressions, so the same bits in double.
template <class T>
T calc_pin_force_N(const RailConstants& r, T lambda_N) {
  using std::abs;
  return abs(lambda_N) / r.three_sin_beta;
}
// f with the constants of the phase (no trigonometry per evaluation): the same bits as above.
template <class T>
T calc_rail_function_m(const RailParams& r, const RailConstants& rc, T hinge_x_m, T hinge_y_m) {
  return hinge_y_m - r.y_m + rc.cot_beta * (hinge_x_m - r.x_m);
}

template <class T>
struct OnRailKinematicsT {
  T x = 0, s = 0;          // hinge offset and half-opening sqrt(l^2 - x^2)
  T x_over_s = 0;          // x / s
  T Y = 0, dY = 0, d2Y = 0;  // upper (driven) frame height and derivatives in x
  T Z = 0, dZ = 0, d2Z = 0;  // lower frame height and derivatives in x
};
using OnRailKinematics = OnRailKinematicsT<double>;

template <class T>
OnRailKinematicsT<T> calc_on_rail(const RailConstants& r, double strut_length_m, T x) {
  using std::sqrt;
  const double c = r.cot_beta;
  const double l = strut_length_m;
  OnRailKinematicsT<T> k;
  k.x = x;
  k.s = sqrt(l * l - x * x);
  const T yh = r.axis_height_m - c * x;
  const T xs = x / k.s;
  const T curv = l * l / (k.s * k.s * k.s);
  k.x_over_s = xs;
  k.Y = yh + k.s;
  k.dY = -c - xs;
  k.d2Y = -curv;
  k.Z = yh - k.s;
  k.dZ = -c + xs;
  k.d2Z = curv;
  return k;
}
inline OnRailKinematics calc_on_rail(const RailParams& r, double strut_length_m, double x) {
  return calc_on_rail(calc_rail_constants(r), strut_length_m, x);
}

// Hinge offset x on the rail for a driven-frame height y = Y(x), written without cancellation
// near the lock: with d = y - y_r and remaining travel to the lock e = (y_r + l) - y,
//   x = (l^2 - d^2) / (c d + sqrt((1 + c^2) l^2 - d^2)),  l^2 - d^2 = e (2 l - e).
// Pass e directly (e.g. v (t_lock - t)) so that no digits are lost as x -> 0.
template <class T>
T calc_x_on_rail_from_travel(const RailConstants& r, double strut_length_m, T travel_to_lock_m) {
  using std::sqrt;
  const double c = r.cot_beta;
  const double l = strut_length_m;
  const T e = travel_to_lock_m;
  const T d = l - e;
  const T num = e * (2.0 * l - e);
  return num / (c * d + sqrt((1.0 + c * c) * l * l - d * d));
}
inline double calc_x_on_rail_from_travel(const RailParams& r, double strut_length_m, double travel_to_lock_m) {
  return calc_x_on_rail_from_travel(calc_rail_constants(r), strut_length_m, travel_to_lock_m);
}

// Rail entry of a bay whose lower frame is held at height z0 (docs/model.md §2, held stack).
// The hinge runs on the quarter circle (l cos th, z0 + l sin th), th in [0, pi/2], and
//   f(th) = R sin(th + phi) - (y_r - z0),  R = l sqrt(1 + c^2),  phi = atan(c),
// which rises then falls on that arc; the pin meets the rail once, from f > 0, iff
//   f(0) = c l - (y_r - z0) > 0   and   f(pi/2) = l - (y_r - z0) < 0.
struct HeldRailEntry {
  bool reachable = false;     // false: the held lower frame never meets the rail
  double theta_rad = 0;       // strut angle from the radial direction at entry
  double hinge_x_m = 0;
  double hinge_y_m = 0;
  double opening_m = 0;       // D at entry
  double upper_height_m = 0;  // driven frame height at entry, z0 + D
};

inline HeldRailEntry calc_held_rail_entry(const RailParams& r, double strut_length_m, double z0) {
  const double c = r.cot_beta();
  const double l = strut_length_m;
  const double h = r.axis_height_m() - z0;
  HeldRailEntry e;
  if (!(c * l - h > 0.0) || !(l - h < 0.0)) return e;
  const double R = l * std::sqrt(1.0 + c * c);
  e.theta_rad = M_PI - std::atan(c) - std::asin(h / R);
  e.reachable = true;
  e.hinge_x_m = l * std::cos(e.theta_rad);
  e.opening_m = 2.0 * l * std::sin(e.theta_rad);
  e.hinge_y_m = z0 + 0.5 * e.opening_m;
  e.upper_height_m = z0 + e.opening_m;
  return e;
}

// Well-posed held entry (docs/model.md §2; docs/model-notes.md "Rail geometry"). With h = y_r - z0,
// f(0) = c l - h is the stowed pin's clearance to the rail and the pin meets the rail on the
// falling branch of f. As h -> l the entry moves to the straight bay (x -> 0): the struts' radial
// speed x' = -D D' / (4 x) grows without bound before the rail takes the pin, and the drive force
// with it (a singular configuration of the held stack). The entry is kept 1e-4 l_s from straight,
// docs/model.md's "singular configuration" margin:
//   cos(th_e) >= delta  <=>  h >= l (c delta + r),  r = sqrt(1 - delta^2),
// and the stowed pin must clear the rail, h < c l (at h = c l it touches it; beyond, the rail
// passes below the stowed hinge and never takes it). The range is empty iff c <= 1 + O(delta),
// i.e. beta >= 45 deg: the rail rises (c l) no more than the hinge does on its arc (l).
inline constexpr double kEntryMarginFraction = 1e-4;
struct HeldEntryRange {
  double h_min_m = 0;  // admissible y_r - z0: [h_min_m, h_below_m)
  double h_below_m = 0;
};
inline HeldEntryRange calc_held_entry_range(const RailParams& r, double strut_length_m) {
  const double c = r.cot_beta(), l = strut_length_m, d = kEntryMarginFraction;
  return {l * (c * d + std::sqrt(1.0 - d * d)), c * l};
}

// The dip of a rail entry (m, >= 0; see the head of this file): how deep the uncaptured pin would
// dip below the rail line. Frame heights y_m (driven), y_lo (lower), their velocities u, w and
// accelerations a_u, a_w at the entry; 0 for a grazing entry (f' = 0, f'' > 0). Continuous in all.
inline double calc_rail_entry_dip_m(const RailParams& r, double strut_length_m, double y_m, double y_lo, double u,
                                    double w, double a_u, double a_w) {
  const double c = r.cot_beta(), l = strut_length_m;
  const double D = y_m - y_lo, Dd = u - w, Ddd = a_u - a_w;
  const double x = std::sqrt(std::max(l * l - 0.25 * D * D, 1e-8 * l * l));  // x >= 1e-4 l (straight bay)
  const double xd = -D * Dd / (4.0 * x);
  const double xdd = -(Dd * Dd + D * Ddd) / (4.0 * x) - xd * xd / x;
  const double fd = 0.5 * (u + w) + c * xd, fdd = 0.5 * (a_u + a_w) + c * xdd;
  const double horizon = l / std::max(std::abs(u), std::abs(fd));
  const double tau = fdd > 0.0 ? std::min(horizon, -fd / fdd) : horizon;  // the continued path's lowest point
  return std::max(0.0, -(fd * tau + 0.5 * fdd * tau * tau)) * std::sin(r.beta_rad);
}

// The margin of a rail entry (m; see the head of this file) from its dip d >= 0 and the slack s of
// the deploying bay's diagonals at the entry (m, l_0 - L; negative when taut): d while they are
// taut, 0 when d = 0 whatever s (a grazing entry), strictly increasing in s+ while d > 0 (slope
// d^2 / (d + s+)^2: 1 at s+ = 0), below 2 d. Continuous in (d, s), at d = s+ = 0 too
// (0 <= d s+ / (d + s+) <= min(d, s+)).
inline double calc_rail_entry_margin_m(double dip_m, double slack_m) {
  const double s = std::max(slack_m, 0.0);
  return s > 0.0 ? dip_m + dip_m * s / (dip_m + s) : dip_m;
}

// Lock: x = 0, upper frame at y_r + l, lower frame lifted to y_r - l.
inline double calc_lock_upper_height_m(const RailParams& r, double strut_length_m) {
  return r.axis_height_m() + strut_length_m;
}
inline double calc_lock_lower_height_m(const RailParams& r, double strut_length_m) {
  return r.axis_height_m() - strut_length_m;
}

}  // namespace truss::model
