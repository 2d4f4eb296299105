#include "stages/held_phase.hpp"

#include <algorithm>
#include <cmath>

#include "numerics/dual.hpp"

namespace truss::stages {

using namespace truss::model;

HeldPhase::HeldPhase(const PhaseContext& ctx, const model::RailConstants& rail) : ctx_(ctx), rail_(rail) {
  const MastParams& mast = *ctx_.mast;
  const int m = ctx_.bay;
  active_.m = m;
  active_.locked_mass_kg = ctx_.locked_mass_kg;
  active_.panel_height_offset_m = ctx_.panel_height_offset_m;
  b2_m_ = calc_diagonal_offset_sq_m2(mast.frame(m - 1), mast.frame(m));
  if (ctx_.kind == PhaseKind::open) {
    active_.lo = m;
    active_.bay_m_in_hinge_coordinate = false;
  } else {
    active_.lo = m - 1;
    active_.bay_m_in_hinge_coordinate = true;
    if (m >= 2) b2_lower_ = calc_diagonal_offset_sq_m2(mast.frame(m - 2), mast.frame(m - 1));
  }
  // The two bays' b^2 once for the phase, not at every evaluation of the frame system.
  if (m >= 2) active_.top_offset_sq_m2[0] = calc_diagonal_offset_sq_m2(mast.frame(m - 2), mast.frame(m - 1));
  active_.top_offset_sq_m2[1] = b2_m_;
}

template <class T>
PhasePointT<T> HeldPhase::calc_point_t(T q, T qdot) const {
  if (ctx_.kind == PhaseKind::open) return calc_open(q, qdot);
  return calc_on_rail(model::calc_on_rail(rail_, strut_length_m(), q), qdot);
}

template <class T>
PhasePointT<T> HeldPhase::calc_point_at_speed_t(T q, double u_m_per_s, PointFields fields) const {
  if (ctx_.kind == PhaseKind::open) return calc_open(q, T(u_m_per_s), fields);
  const model::OnRailKinematicsT<T> kin = model::calc_on_rail(rail_, strut_length_m(), q);
  return calc_on_rail(kin, T(u_m_per_s) / kin.dY, fields);
}

double HeldPhase::calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& /*scratch*/) const {
  const PhasePoint p = ctx_.kind == PhaseKind::open ? calc_open(q[0], qdot[0], PointFields::motion)
                                                    : calc_on_rail(calc_kinematics(q[0]), qdot[0], PointFields::motion);
  qddot[0] = p.qddot;
  return p.drive_force_N * p.u_m_per_s;
}

PhasePoint HeldPhase::calc_loads(const double* q, const double* qdot, double* qddot, PhaseScratch& /*scratch*/) const {
  const PhasePoint p = ctx_.kind == PhaseKind::open ? calc_open(q[0], qdot[0], PointFields::loads)
                                                    : calc_on_rail(calc_kinematics(q[0]), qdot[0], PointFields::loads);
  qddot[0] = p.qddot;
  return p;
}

PhasePoint HeldPhase::calc_point(double q, double qdot, PhaseScratch& /*scratch*/) const {
  return calc_point_t(q, qdot);
}

PhasePoint HeldPhase::calc_point(double q, double qdot) const { return calc_point_t(q, qdot); }

double HeldPhase::calc_driven_speed_m_per_s(double q, double qdot) const {
  if (ctx_.kind == PhaseKind::open) return qdot;
  return model::calc_on_rail(rail_, strut_length_m(), q).dY * qdot;
}

template <class T>
PhasePointT<T> HeldPhase::calc_open(T y, T u, PointFields fields) const {
  const MastParams& mast = *ctx_.mast;
  const int m = ctx_.bay;
  const BayParams& bay = mast.bay(m);
  const T ys[2] = {ctx_.lower_held_height_m, y}, vs[2] = {0.0, u};  // frames m-1, m
  model::SmallFrameSystem<T> sys;
  calc_frame_system(mast, active_, ys, vs, m - 1, sys);
  PhasePointT<T> p;
  p.q = y; p.qdot = u;
  p.y_driven_m = y; p.y_lower_m = ctx_.lower_held_height_m;
  p.u_m_per_s = u; p.w_m_per_s = 0.0;
  const T D = y - ctx_.lower_held_height_m;
  if (fields == PointFields::all) p.hinge_x_m = calc_hinge_offset_m(bay, D);
  p.hinge_y_m = ctx_.lower_held_height_m + 0.5 * D;
  const T M = sys.diag[0];
  const T R = sys.velocity_terms[0] + sys.spring_forces[0];
  p.static_drive_force_N = -sys.spring_forces[0];
  if (ctx_.drive.mode == model::DriveMode::velocity) {
    p.qddot = 0.0;
    p.drive_force_N = -R;
  } else {
    p.drive_force_N = ctx_.drive.calc_force_N(u, ctx_.direction);
    p.qddot = (R + p.drive_force_N) / M;
  }
  if (fields == PointFields::motion) return p;
  p.diagonal_tension_N = calc_diagonal_tension_N(bay, b2_m_, D);
  p.mass_yy = M;
  if (fields == PointFields::loads) return p;
  p.kinetic_energy_J = 0.5 * M * u * u;
  p.potential_energy_J = calc_bay_potential_J(bay, b2_m_, D);
  return p;
}

template <class T>
PhasePointT<T> HeldPhase::calc_on_rail(const model::OnRailKinematicsT<T>& kin, T xi, PointFields fields) const {
  using std::abs;
  const MastParams& mast = *ctx_.mast;
  const int m = ctx_.bay;
  const BayParams& bay = mast.bay(m);
  const double c = rail_.cot_beta;
  const T x = kin.x;
  const T u = kin.dY * xi;
  const T w = kin.dZ * xi;
  const T ys[3] = {ctx_.lower_held_height_m, kin.Z, kin.Y}, vs[3] = {0.0, w, u};  // frames m-2, m-1, m
  // ys[0] is frame m-2, read only when m >= 2 (frame 0 has no bay below it).
  model::SmallFrameSystem<T> sys;
  calc_frame_system(mast, active_, m >= 2 ? ys : ys + 1, m >= 2 ? vs : vs + 1, m >= 2 ? m - 2 : m - 1, sys);
  const T A_ll = sys.diag[0], A_mm = sys.diag[1], A_ml = sys.sub[1];
  const T r_l = sys.velocity_terms[0] + sys.spring_forces[0];
  const T r_m = sys.velocity_terms[1] + sys.spring_forces[1];
  // 2 x / s and 2 l^2 / s^3 from the kinematics' x / s and l^2 / s^3 (a factor 2 is exact).
  const T k = 2.0 * kin.x_over_s;
  const T dk = 2.0 * kin.d2Z;
  const T g = calc_g_hinge(bay, x);
  const T dg = calc_dg_hinge_dx(bay, x);
  const T xi2 = xi * xi;
  const T M_yy = A_mm + 2.0 * A_ml + A_ll;
  const T M_yx = k * (A_ml + A_ll);
  const T M_xx = k * k * A_ll + 2.0 * g;
  const T R_y0 = r_m + r_l - (A_ml + A_ll) * dk * xi2;  // without the drive force
  const T R_x = k * (r_l - A_ll * dk * xi2) - dg * xi2;
  const T gamma = c + kin.x_over_s;  // = -Y'(x) = df/dx in (y_m, x)

  PhasePointT<T> p;
  p.q = x; p.qdot = xi;
  p.y_driven_m = kin.Y; p.y_lower_m = kin.Z;
  p.u_m_per_s = u; p.w_m_per_s = w;
  p.hinge_x_m = x; p.hinge_y_m = rail_.axis_height_m - c * x;
  T yddot;
  if (ctx_.drive.mode == model::DriveMode::velocity) {
    p.qddot = kin.d2Y * xi2 / gamma;
    yddot = 0.0;
    p.lambda_N = (M_yx * yddot + M_xx * p.qddot - R_x) / gamma;
    p.drive_force_N = M_yy * yddot + M_yx * p.qddot - R_y0 - p.lambda_N;
  } else {
    p.drive_force_N = ctx_.drive.calc_force_N(u, ctx_.direction);
    const T R_y = R_y0 + p.drive_force_N;
    const T mu = M_xx - 2.0 * gamma * M_yx + gamma * gamma * M_yy;
    p.qddot = (R_x - gamma * R_y - (M_yx - gamma * M_yy) * kin.d2Y * xi2) / mu;
    if (fields == PointFields::motion) return p;
    yddot = kin.dY * p.qddot + kin.d2Y * xi2;
    p.lambda_N = M_yy * yddot + M_yx * p.qddot - R_y;
  }
  p.pin_force_N = calc_pin_force_N(rail_, p.lambda_N);
  // At rest (xi = 0): F + Q_y + lambda = 0 and Q_x + gamma lambda = 0 with the springs' Q_y = s_m + s_l,
  // Q_x = k s_l, so F = -(s_m + s_l) + k s_l / gamma = dU/dY along the rail.
  p.static_drive_force_N = -(sys.spring_forces[1] + sys.spring_forces[0]) + k * sys.spring_forces[0] / gamma;
  const T D = 2.0 * kin.s;
  T tension = calc_diagonal_tension_N(bay, b2_m_, D);
  if (fields == PointFields::all) p.potential_energy_J = calc_bay_potential_J(bay, b2_m_, D);
  if (m >= 2) {
    const BayParams& lower = mast.bay(m - 1);
    const T Dl = kin.Z - ctx_.lower_held_height_m;
    const T tension_lower = calc_diagonal_tension_N(lower, b2_lower_, Dl);
    if (tension < tension_lower) tension = tension_lower;  // std::max
    if (fields == PointFields::all) p.potential_energy_J += calc_bay_potential_J(lower, b2_lower_, Dl);
  }
  p.diagonal_tension_N = tension;
  p.mass_yy = M_yy; p.mass_yx = M_yx; p.mass_xx = M_xx;
  p.rail_slope = gamma;
  p.rail_residual_m = abs(calc_rail_function_m(mast.rail, rail_, x, 0.5 * (kin.Y + kin.Z)));
  if (fields == PointFields::loads) return p;
  p.kinetic_energy_J = 0.5 * (M_yy * u * u + 2.0 * M_yx * u * xi + M_xx * xi2);
  return p;
}

// The closed form in double (every solver) and in dual numbers (time derivatives: the velocity
// mode's closed-form solver).
template PhasePointT<double> HeldPhase::calc_point_t(double, double) const;
template PhasePointT<numerics::Dual> HeldPhase::calc_point_t(numerics::Dual, numerics::Dual) const;
template PhasePointT<double> HeldPhase::calc_point_at_speed_t(double, double, PointFields) const;
template PhasePointT<numerics::Dual> HeldPhase::calc_point_at_speed_t(numerics::Dual, double, PointFields) const;
// In extended precision: the independent values of the tests (tests/numeric/test_closed_form.cpp).
template PhasePointT<long double> HeldPhase::calc_point_at_speed_t(long double, double, PointFields) const;

TwoFrameMass calc_two_frame_mass(const MastParams& mast, int m, double locked_mass_kg, double panel_height_offset_m, double y_lower,
                                 double y_driven) {
  ActiveFrames a;
  a.lo = m - 1;
  a.m = m;
  a.locked_mass_kg = locked_mass_kg;
  a.panel_height_offset_m = panel_height_offset_m;
  SmallFrameSystem<double> sys;
  const double y[3] = {0.0, y_lower, y_driven};
  const double v[3] = {0.0, 0.0, 0.0};
  if (m >= 2) calc_frame_system(mast, a, y, v, m - 2, sys);
  else calc_frame_system(mast, a, y + 1, v + 1, m - 1, sys);
  return {sys.diag[0], sys.sub[1], sys.diag[1]};
}

}  // namespace truss::stages
