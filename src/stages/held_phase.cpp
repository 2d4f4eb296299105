#include "stages/held_phase.hpp"

#include <algorithm>
#include <cmath>

namespace truss::stages {

using namespace truss::model;

HeldPhase::HeldPhase(const PhaseContext& ctx) : ctx_(ctx), rail_(model::calc_rail_constants(ctx.mast->rail)) {
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
}

PhasePoint HeldPhase::calc_point(double q, double qdot, PhaseScratch& scratch) const {
  return ctx_.kind == PhaseKind::open ? calc_open(q, qdot, scratch) : calc_on_rail(q, qdot, scratch);
}

PhasePoint HeldPhase::calc_point(double q, double qdot) const {
  PhaseScratch scratch;
  return calc_point(q, qdot, scratch);
}

double HeldPhase::calc_driven_speed_m_per_s(double q, double qdot) const {
  if (ctx_.kind == PhaseKind::open) return qdot;
  return model::calc_on_rail(ctx_.mast->rail, strut_length_m(), q).dY * qdot;
}

PhasePoint HeldPhase::calc_open(double y, double u, PhaseScratch& sys) const {
  const MastParams& mast = *ctx_.mast;
  const int m = ctx_.bay;
  const BayParams& bay = mast.bay(m);
  const double ys[2] = {ctx_.lower_held_height_m, y}, vs[2] = {0.0, u};  // frames m-1, m
  calc_frame_system(mast, active_, ys, vs, m - 1, sys);
  PhasePoint p;
  p.q = y; p.qdot = u;
  p.y_driven_m = y; p.y_lower_m = ctx_.lower_held_height_m;
  p.u_m_per_s = u; p.w_m_per_s = 0.0;
  const double D = y - ctx_.lower_held_height_m;
  p.hinge_x_m = calc_hinge_offset_m(bay, D);
  p.hinge_y_m = ctx_.lower_held_height_m + 0.5 * D;
  const double M = sys.diag[0];
  const double R = sys.velocity_terms[0] + sys.spring_forces[0];
  p.static_drive_force_N = -sys.spring_forces[0];
  if (ctx_.drive.mode == model::DriveMode::velocity) {
    p.qddot = 0.0;
    p.drive_force_N = -R;
  } else {
    p.drive_force_N = ctx_.drive.calc_force_N(u, ctx_.direction);
    p.qddot = (R + p.drive_force_N) / M;
  }
  p.diagonal_tension_N = calc_diagonal_tension_N(bay, b2_m_, D);
  p.kinetic_energy_J = 0.5 * M * u * u;
  p.mass_yy = M;
  p.potential_energy_J = calc_bay_potential_J(bay, b2_m_, D);
  return p;
}

PhasePoint HeldPhase::calc_on_rail(double x, double xi, PhaseScratch& sys) const {
  const MastParams& mast = *ctx_.mast;
  const int m = ctx_.bay;
  const BayParams& bay = mast.bay(m);
  const double l = bay.strut_length_m;
  const double c = rail_.cot_beta;
  const OnRailKinematics kin = model::calc_on_rail(rail_, l, x);
  const double u = kin.dY * xi;
  const double w = kin.dZ * xi;
  const double ys[3] = {ctx_.lower_held_height_m, kin.Z, kin.Y}, vs[3] = {0.0, w, u};  // frames m-2, m-1, m
  // ys[0] is frame m-2, read only when m >= 2 (frame 0 has no bay below it).
  calc_frame_system(mast, active_, m >= 2 ? ys : ys + 1, m >= 2 ? vs : vs + 1, m >= 2 ? m - 2 : m - 1, sys);
  const double A_ll = sys.diag[0], A_mm = sys.diag[1], A_ml = sys.sub[1];
  const double r_l = sys.velocity_terms[0] + sys.spring_forces[0];
  const double r_m = sys.velocity_terms[1] + sys.spring_forces[1];
  const double k = 2.0 * x / kin.s;
  const double dk = 2.0 * l * l / (kin.s * kin.s * kin.s);
  const double g = calc_g_hinge(bay, x);
  const double dg = calc_dg_hinge_dx(bay, x);
  const double xi2 = xi * xi;
  const double M_yy = A_mm + 2.0 * A_ml + A_ll;
  const double M_yx = k * (A_ml + A_ll);
  const double M_xx = k * k * A_ll + 2.0 * g;
  const double R_y0 = r_m + r_l - (A_ml + A_ll) * dk * xi2;  // without the drive force
  const double R_x = k * (r_l - A_ll * dk * xi2) - dg * xi2;
  const double gamma = c + x / kin.s;  // = -Y'(x) = df/dx in (y_m, x)

  PhasePoint p;
  p.q = x; p.qdot = xi;
  p.y_driven_m = kin.Y; p.y_lower_m = kin.Z;
  p.u_m_per_s = u; p.w_m_per_s = w;
  p.hinge_x_m = x; p.hinge_y_m = rail_.axis_height_m - c * x;
  double yddot;
  if (ctx_.drive.mode == model::DriveMode::velocity) {
    p.qddot = kin.d2Y * xi2 / gamma;
    yddot = 0.0;
    p.lambda_N = (M_yx * yddot + M_xx * p.qddot - R_x) / gamma;
    p.drive_force_N = M_yy * yddot + M_yx * p.qddot - R_y0 - p.lambda_N;
  } else {
    p.drive_force_N = ctx_.drive.calc_force_N(u, ctx_.direction);
    const double R_y = R_y0 + p.drive_force_N;
    const double mu = M_xx - 2.0 * gamma * M_yx + gamma * gamma * M_yy;
    p.qddot = (R_x - gamma * R_y - (M_yx - gamma * M_yy) * kin.d2Y * xi2) / mu;
    yddot = kin.dY * p.qddot + kin.d2Y * xi2;
    p.lambda_N = M_yy * yddot + M_yx * p.qddot - R_y;
  }
  p.pin_force_N = calc_pin_force_N(rail_, p.lambda_N);
  // At rest (xi = 0): F + Q_y + lambda = 0 and Q_x + gamma lambda = 0 with the springs' Q_y = s_m + s_l,
  // Q_x = k s_l, so F = -(s_m + s_l) + k s_l / gamma = dU/dY along the rail.
  p.static_drive_force_N = -(sys.spring_forces[1] + sys.spring_forces[0]) + k * sys.spring_forces[0] / gamma;
  const double D = 2.0 * kin.s;
  double tension = calc_diagonal_tension_N(bay, b2_m_, D);
  double U = calc_bay_potential_J(bay, b2_m_, D);
  if (m >= 2) {
    const BayParams& lower = mast.bay(m - 1);
    const double Dl = kin.Z - ctx_.lower_held_height_m;
    tension = std::max(tension, calc_diagonal_tension_N(lower, b2_lower_, Dl));
    U += calc_bay_potential_J(lower, b2_lower_, Dl);
  }
  p.diagonal_tension_N = tension;
  p.kinetic_energy_J = 0.5 * (M_yy * u * u + 2.0 * M_yx * u * xi + M_xx * xi2);
  p.potential_energy_J = U;
  p.mass_yy = M_yy; p.mass_yx = M_yx; p.mass_xx = M_xx;
  p.rail_slope = gamma;
  p.rail_residual_m = std::abs(calc_rail_function_m(mast.rail, x, 0.5 * (kin.Y + kin.Z)));
  return p;
}

TwoFrameMass calc_two_frame_mass(const MastParams& mast, int m, double locked_mass_kg, double panel_height_offset_m, double y_lower,
                                 double y_driven) {
  ActiveFrames a;
  a.lo = m - 1;
  a.m = m;
  a.locked_mass_kg = locked_mass_kg;
  a.panel_height_offset_m = panel_height_offset_m;
  FrameSystem sys;
  const double y[3] = {0.0, y_lower, y_driven};
  const double v[3] = {0.0, 0.0, 0.0};
  if (m >= 2) calc_frame_system(mast, a, y, v, m - 2, sys);
  else calc_frame_system(mast, a, y + 1, v + 1, m - 1, sys);
  return {sys.diag[0], sys.sub[1], sys.diag[1]};
}

}  // namespace truss::stages
