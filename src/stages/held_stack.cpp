#include "stages/held_stack.hpp"

#include <cmath>

#include "integrators/factory.hpp"
#include "model/impacts.hpp"
#include "model/rail.hpp"

namespace truss::stages {

using namespace truss::model;

HeldStack::HeldStack(const MastParams& mast, const RunnerOptions& opts)
    : StackModel(mast, opts), rail_(calc_rail_constants(mast.rail)) {
  if (!drive_holds_speed_)
    integrator_ = integrators::make_integrator(opts.run.integrator, opts.calc_integrator_options());
}

StackEvent HeldStack::start_stage(const StageSpec& s, bool first_stage) {
  StackEvent e;
  const double v = opts_.drive.speed_m_per_s;
  if (s.start == StageStart::from_rest_or_kick && drive_holds_speed_) {
    // Impulsive start of the driven part from rest (docs/model.md §4): a lossless ramp of the drive.
    const HeldPhase open(make_context(s, PhaseKind::open, 0.0), rail_);
    const PhasePoint p0 = open.calc_point(s.phases[0].q_start, dir_ * v);
    e.evals = 1;
    u_ = dir_ * v;
    const DriveRamp ramp = calc_drive_ramp(p0.mass_yy, u_);
    e.start_drive_impulse_Ns = ramp.impulse_Ns;
    e.drive_work_J = ramp.work_J;
  }
  if (s.start != StageStart::unlock) return e;
  const PhasePoint p0 = HeldPhase(make_context(s, PhaseKind::on_rail, 0.0), rail_).calc_point(0.0, 0.0);
  e.evals = 1;
  const double c = rail_.cot_beta;
  if (drive_holds_speed_ && first_stage) {
    // The mast starts from rest: the drive ramps the driven frame and, through the rail, the
    // hinge (x' = -u / c) up together, lossless; no impact, so no latch energy (docs/model.md §2
    // charges it for the unlock of a moving mast only). Mass along the constrained motion, with
    // M_yx = 0 at x = 0: M_yy + M_xx / c^2.
    u_ = dir_ * v;
    xi_ = -u_ / c;
    const DriveRamp ramp = calc_drive_ramp(p0.mass_yy + p0.mass_xx / (c * c), u_);
    e.start_drive_impulse_Ns = ramp.impulse_Ns;
    e.drive_work_J = ramp.work_J;
    e.rail_impulse_Ns = p0.mass_xx * xi_ / c;  // the rail gives the hinge M_xx xi = c Lambda
    return e;
  }
  const UnlockImpact imp = calc_unlock_impact(p0.mass_yy, p0.mass_xx, c, u_, drive_holds_speed_);
  if (!drive_holds_speed_) u_ += imp.du_m_per_s;
  xi_ = imp.hinge_speed_m_per_s;
  e.rail_impulse_Ns = imp.rail_impulse_Ns;
  e.drive_work_J = imp.drive_work_J;  // 0 unless the drive holds its speed
  e.energy_loss_J = imp.energy_loss_J;
  return e;
}

PhaseSegment HeldStack::begin_segment(const StageSpec& s, const PhaseSpec& ph, bool /*first*/, double /*t_s*/,
                                      const integrators::IntegratorOptions& io) {
  PhaseContext ctx = make_context(s, ph.kind, ph.lower_held_height_m);
  ctx.q_end = ph.q_end;
  ctx.sign_q = ph.q_end > ph.q_start ? 1.0 : -1.0;
  phase_.emplace(ctx, rail_);
  q0_ = ph.q_start;
  qdot0_ = ph.kind == PhaseKind::open ? u_ : xi_;
  PhaseSegment seg;
  seg.q = &q0_;
  seg.qdot = &qdot0_;
  seg.creep_reference_m_per_s = std::abs(u_);
  if (drive_holds_speed_) seg.solver = &closed_form_.emplace(*phase_, opts_.peak_samples_per_piece, peak_work_);
  else seg.solver = &stepper_.emplace(*phase_, *integrator_, io);
  return seg;
}

StackEvent HeldStack::end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, double /*t_s*/) {
  StackEvent e;
  const double u_end = p_end.u_m_per_s;
  switch (ph.end) {
    case PhaseEnd::rail_entry: {
      // Plastic impact of the held lower frame with the rail (docs/model.md §2), in frame heights.
      const TwoFrameMass M = calc_two_frame_mass(mast_, s.bay, s.locked_mass_kg, s.panel_height_offset_m,
                                                 ph.lower_held_height_m, p_end.y_driven_m);
      const double x = s.entry_hinge_x_m, D = p_end.y_driven_m - ph.lower_held_height_m;
      const FrameImpact imp = calc_rail_entry_impact(M, calc_rail_gradient(rail_.cot_beta, D, x), u_end,
                                                     drive_holds_speed_);
      u_ = u_end + imp.du_m_per_s;
      xi_ = u_ / calc_on_rail(rail_, mast_.bay(s.bay).strut_length_m, x).dY;
      e.rail_impulse_Ns = imp.rail_impulse_Ns;
      e.drive_impulse_Ns = imp.drive_impulse_Ns;
      e.energy_loss_J = imp.energy_loss_J;
      e.drive_work_J = imp.drive_work_J;
      return e;
    }
    case PhaseEnd::rail_exit: {
      // The lower frame lands on the stack: plastic, its velocity w -> 0.
      const TwoFrameMass M = calc_two_frame_mass(mast_, s.bay, s.locked_mass_kg, s.panel_height_offset_m, p_end.y_lower_m,
                                                 p_end.y_driven_m);
      const FrameImpact imp = calc_rail_exit_impact(M, p_end.w_m_per_s, u_end, drive_holds_speed_);
      u_ = u_end + imp.du_m_per_s;
      e.landing_impulse_Ns = std::abs(imp.stack_impulse_Ns);
      e.drive_impulse_Ns = imp.drive_impulse_Ns;
      e.energy_loss_J = imp.energy_loss_J;
      e.drive_work_J = imp.drive_work_J;
      return e;
    }
    case PhaseEnd::lock: u_ = u_end; return e;  // the latch keeps y_m' (the loop books its loss)
    case PhaseEnd::reach_height: u_ = s.final_landing ? 0.0 : u_end; return e;  // frame n lands: the mast stops
  }
  return e;
}

}  // namespace truss::stages
