#include "stages/phase_kinematic.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "model/bay.hpp"
#include "model/rail.hpp"
#include "numerics/dual.hpp"
#include "stages/closed_form_peaks.hpp"

namespace truss::stages {

using namespace truss::model;
using numerics::Dual;

namespace {

// The values of a point computed in dual numbers.
PhasePoint calc_values(const PhasePointT<Dual>& d) {
  PhasePoint p;
  p.q = d.q.v; p.qdot = d.qdot.v; p.qddot = d.qddot.v;
  p.y_driven_m = d.y_driven_m.v; p.y_lower_m = d.y_lower_m.v;
  p.u_m_per_s = d.u_m_per_s.v; p.w_m_per_s = d.w_m_per_s.v;
  p.hinge_x_m = d.hinge_x_m.v; p.hinge_y_m = d.hinge_y_m.v;
  p.drive_force_N = d.drive_force_N.v;
  p.static_drive_force_N = d.static_drive_force_N.v;
  p.lambda_N = d.lambda_N.v;
  p.pin_force_N = d.pin_force_N.v;
  p.diagonal_tension_N = d.diagonal_tension_N.v;
  p.kinetic_energy_J = d.kinetic_energy_J.v;
  p.potential_energy_J = d.potential_energy_J.v;
  p.rail_residual_m = d.rail_residual_m.v;
  p.mass_yy = d.mass_yy.v; p.mass_yx = d.mass_yx.v; p.mass_xx = d.mass_xx.v;
  p.rail_slope = d.rail_slope.v;
  p.rail_distance_m = d.rail_distance_m.v;
  p.min_bay_opening_m = d.min_bay_opening_m.v;
  return p;
}

// The peak quantities of a point and their time derivatives.
RatedSample make_rated_sample(double t, const PhasePointT<Dual>& d, double direction) {
  RatedSample s;
  s.t = t;
  for (int k = 0; k < kQuantityCount; ++k) {
    const Dual q = calc_peak_quantity(k, d, direction);
    s.q[static_cast<std::size_t>(k)] = q.v;
    s.dq[static_cast<std::size_t>(k)] = q.d;
  }
  return s;
}

// Driven-frame height at which bay m's diagonals become taut in this phase (NaN: never).
double calc_taut_height_m(const HeldPhase& phase) {
  const PhaseContext& ctx = phase.context();
  const MastParams& mast = *ctx.mast;
  const int m = ctx.bay;
  const double l = phase.strut_length_m();
  const double Dt = calc_taut_opening_m(mast.bay(m), calc_diagonal_offset_sq_m2(mast.frame(m - 1), mast.frame(m)));
  if (!(Dt > 0.0)) return kNaN;
  if (ctx.kind == PhaseKind::open) return ctx.lower_held_height_m + Dt;
  if (!(Dt < 2.0 * l)) return kNaN;
  return calc_on_rail(phase.get_rail_constants(), l, std::sqrt(l * l - 0.25 * Dt * Dt)).Y;
}

}  // namespace

PhaseOutcome KinematicPhaseSolver::solve(const PhaseStart& start, PhaseSinks& sinks) {
  const PhaseContext& ctx = phase_.context();
  const RailConstants& rail = phase_.get_rail_constants();
  const double l = phase_.strut_length_m();
  const double dir = ctx.direction;
  const double v = ctx.drive.speed_m_per_s;
  const bool open = ctx.kind == PhaseKind::open;
  const double q_start = start.q[0];
  PhaseOutcome out;
  const double y_begin = open ? q_start : calc_on_rail(rail, l, q_start).Y;
  const double y_finish = open ? ctx.q_end : calc_on_rail(rail, l, ctx.q_end).Y;
  const double t0 = start.t_s, t1 = t0 + std::abs(y_finish - y_begin) / v;
  // The run's wall-time cap: a phase costs a bounded number of evaluations here, so the cap is
  // checked at the start of every few phases (PhaseSinks::check_clock) and, after the history
  // (the cost of long histories), at its end.
  if (sinks.check_clock && std::chrono::steady_clock::now() > sinks.deadline) {
    out.reason = PhaseEndReason::wall_time;
    out.t_end_s = t0;
    return out;
  }
  // The phase at time tt, in dual numbers seeded with d/dt (T = Dual) or in double.
  auto eval_t = [&]<class T>(double tt, T, PointFields fields) {
    tt = std::clamp(tt, t0, t1);
    if (open) {
      // distance from the phase end, measured from the nearer end for exactness
      const double y = (tt - t0 <= t1 - tt) ? y_begin + dir * v * (tt - t0) : y_finish - dir * v * (t1 - tt);
      return phase_.calc_point_at_speed_t(numerics::make_variable<T>(y, dir * v), dir * v, fields);
    }
    // travel to the lock, exact near it: deploy ends at the lock, retraction starts there
    const T e = dir > 0 ? numerics::make_variable<T>(v * (t1 - tt), -v) : numerics::make_variable<T>(v * (tt - t0), v);
    return phase_.calc_point_at_speed_t(calc_x_on_rail_from_travel(rail, l, e), dir * v, fields);
  };
  // Inside the phase the loads suffice; its end points carry the energies and the end state.
  PhasePoint p0, p1;
  auto rated = [&](double tt) {
    ++out.evals;
    tt = std::clamp(tt, t0, t1);
    const bool end = tt == t0 || tt == t1;
    const PhasePointT<Dual> d = eval_t(tt, Dual(), end ? PointFields::all : PointFields::loads);
    if (tt == t0) p0 = calc_values(d);
    if (tt == t1) p1 = calc_values(d);
    return make_rated_sample(tt, d, dir);
  };
  // Smooth pieces: split where bay m's diagonals become taut (a kink of the force).
  double cut = kNaN;
  const double y_taut = calc_taut_height_m(phase_);
  if (std::isfinite(y_taut)) {
    const double tc = t0 + (y_taut - y_begin) / (dir * v);
    if (tc > t0 && tc < t1) cut = tc;
  }
  std::vector<RatedSample>& samples = work_.samples;
  samples.clear();
  const int ns = std::max(3, samples_per_piece_);
  const double bounds[3] = {t0, std::isfinite(cut) ? cut : t1, t1};
  for (int piece = 0; piece < (std::isfinite(cut) ? 2 : 1); ++piece) {
    const double a = bounds[piece], b = bounds[piece + 1];
    if (piece > 0) {
      // The kink: the value is the left piece's last; the slopes are the right piece's, from
      // just past it (the closed form takes the slack branch or the taut one at the kink itself).
      RatedSample k = rated(a + 1e-9 * (b - a));
      k.t = a;
      k.q = samples.back().q;
      k.kink_before = true;
      samples.push_back(k);
    }
    for (int i = (piece == 0 ? 0 : 1); i < ns; ++i)
      samples.push_back(rated(i + 1 == ns ? b : a + (b - a) * i / (ns - 1)));
  }
  // Drive work of the smooth motion from the energies at the phase ends: in velocity mode the
  // rail (ideal) and the held frames (at rest) do no work, so W = dT + dU of the moving bays.
  out.drive_work_J = (p1.kinetic_energy_J + p1.potential_energy_J) - (p0.kinetic_energy_J + p0.potential_energy_J);
  // The held stack has no rail approach or bay overlap (free stack); its speed is prescribed.
  std::array<PeakSearch, kQuantityCount> search;
  search.fill(PeakSearch::full);
  search[kRailApproach] = search[kOverlap] = PeakSearch::none;
  search[kSpeed] = PeakSearch::samples;
  absorb_rated_peaks(work_, sinks.peaks, rated, search);
  sinks.peaks.max_rail_residual =
      std::max({sinks.peaks.max_rail_residual, p0.rail_residual_m, p1.rail_residual_m});
  // The history and the end point use the plain evaluation.
  if (sinks.history.enabled()) {
    auto plain = [&](double tt) { ++out.evals; return eval_t(tt, 0.0, PointFields::all); };
    const bool in_time = sinks.history.sample(plain, t0, t1, ctx.bay, sinks.deadline);
    if (!in_time || std::chrono::steady_clock::now() > sinks.deadline) out.reason = PhaseEndReason::wall_time;
  }
  out.t_end_s = t1;
  out.end = p1;     // the last sample is at t1, in the same arithmetic as a plain evaluation
  out.end.q = ctx.q_end;  // the event is exact in closed form
  return out;
}

}  // namespace truss::stages
