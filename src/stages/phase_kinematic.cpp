#include "stages/phase_kinematic.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "model/bay.hpp"
#include "model/rail.hpp"
#include "numerics/gauss_kronrod.hpp"

namespace truss::stages {

using namespace truss::model;

PhaseOutcome KinematicPhaseSolver::solve(const PhaseStart& start, PhaseSinks& sinks) {
  const PhaseContext& ctx = phase_.context();
  const MastParams& mast = *ctx.mast;
  const int m = ctx.bay;
  const double l = phase_.strut_length_m();
  const double dir = ctx.direction;
  const double v = ctx.drive.speed_m_per_s;
  const bool open = ctx.kind == PhaseKind::open;
  const double q_start = start.q[0];
  PhaseOutcome out;
  PhaseScratch scratch;
  const double y_begin = open ? q_start : calc_on_rail(mast.rail, l, q_start).Y;
  const double y_finish = open ? ctx.q_end : calc_on_rail(mast.rail, l, ctx.q_end).Y;
  const double t0 = start.t_s, t1 = t0 + std::abs(y_finish - y_begin) / v;
  // The run's wall-time cap (issue 13): checked at the start and every 1024 evaluations; past it,
  // evaluations return NaN (the quadrature stops on a non-finite piece) and the phase ends with
  // reason wall_time at its start time.
  bool timed_out = std::chrono::steady_clock::now() > sinks.deadline;
  auto timed_out_at = [&] {
    out.reason = PhaseEndReason::wall_time;
    out.t_end_s = t0;
    out.drive_work_J = 0.0;
    return out;
  };
  if (timed_out) return timed_out_at();
  auto eval_point = [&](double tt) {
    tt = std::clamp(tt, t0, t1);
    if (open) {
      // distance from the phase end, measured from the nearer end for exactness
      const double y = (tt - t0 <= t1 - tt) ? y_begin + dir * v * (tt - t0) : y_finish - dir * v * (t1 - tt);
      return phase_.calc_point(y, dir * v, scratch);
    }
    // travel to the lock, exact near it: deploy ends at the lock, retraction starts there
    const double e = dir > 0 ? v * (t1 - tt) : v * (tt - t0);
    const double x = calc_x_on_rail_from_travel(mast.rail, l, e);
    const OnRailKinematics kin = calc_on_rail(mast.rail, l, x);
    return phase_.calc_point(x, dir * v / kin.dY, scratch);
  };
  auto eval = [&](double tt) {
    if ((++out.evals & 1023) == 0 && std::chrono::steady_clock::now() > sinks.deadline) timed_out = true;
    PhasePoint p = eval_point(tt);
    if (timed_out) p.drive_force_N = kNaN;
    return p;
  };
  // Smooth pieces: split where bay m's diagonals become taut (a kink of the force).
  std::vector<double> cuts{t0, t1};
  const double Dt = calc_taut_opening_m(mast.bay(m), calc_diagonal_offset_sq_m2(mast.frame(m - 1), mast.frame(m)));
  if (Dt > 0.0) {
    double y_taut = kNaN;
    if (open) y_taut = ctx.lower_held_height_m + Dt;
    else if (Dt < 2.0 * l) y_taut = calc_on_rail(mast.rail, l, std::sqrt(l * l - 0.25 * Dt * Dt)).Y;
    if (std::isfinite(y_taut)) {
      const double tc = t0 + (y_taut - y_begin) / (dir * v);
      if (tc > t0 && tc < t1) cuts.insert(cuts.begin() + 1, tc);
    }
  }
  sinks.phase_peaks.reset(dir);
  const int ns = std::max(3, samples_per_piece_);
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double a = cuts[k], b = cuts[k + 1];
    double f_scale = 1.0;
    for (int i = (k == 0 ? 0 : 1); i < ns; ++i) {
      const double ti = a + (b - a) * i / (ns - 1);
      const PhasePoint pi = eval(ti);
      sinks.phase_peaks.feed(ti, pi);
      f_scale = std::max(f_scale, std::abs(pi.drive_force_N));
    }
    // Drive work of the smooth motion: integral of F u dt, F from inverse dynamics.
    out.drive_work_J += numerics::integrate_gk15([&](double tt) { const PhasePoint p = eval(tt); return p.drive_force_N * p.u_m_per_s; },
                                                 a, b, 1e-11 * f_scale * v * (b - a));  // |K15 - G7| bound: K15 is far better
  }
  if (timed_out) return timed_out_at();
  sinks.peaks.absorb(sinks.phase_peaks, [&](double tt, const HermiteSpan&) { return eval(tt); }, 1e-12 * std::max(1.0, t1));
  // The history and the end point use the plain evaluation: they are exact whatever the clock says.
  const bool in_time = sinks.history.sample([&](double tt) { ++out.evals; return eval_point(tt); }, t0, t1, m, sinks.deadline);
  // The wall-time cap holds in closed form too (long histories are the cost here): the phase's
  // loads and work are complete, its history may not be; the run ends at the phase's end.
  if (!in_time || std::chrono::steady_clock::now() > sinks.deadline) out.reason = PhaseEndReason::wall_time;
  out.t_end_s = t1;
  out.end = eval_point(t1);
  ++out.evals;
  out.end.q = ctx.q_end;  // the event is exact in closed form
  return out;
}

}  // namespace truss::stages
