#include "stages/stage_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "integrators/factory.hpp"
#include "model/impacts.hpp"
#include "model/rail.hpp"
#include "stages/energy.hpp"
#include "stages/free_phase.hpp"
#include "stages/free_stack.hpp"
#include "stages/held_phase.hpp"
#include "stages/phase_dynamic.hpp"
#include "stages/phase_kinematic.hpp"

namespace truss::stages {

using namespace truss::model;

namespace {

class StageLoop {
 public:
  StageLoop(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts);
  RunResult run();

 private:
  PhaseContext make_context(const StageSpec& s, PhaseKind kind, double lower_held_height_m) const {
    return {&mast_, kind, s.bay, lower_held_height_m, s.locked_mass_kg, s.panel_height_offset_m, opts_.drive, dir_, 0.0, 1.0};
  }
  void start_stage(const StageSpec& s, BayResult& br);
  void run_phase(const StageSpec& s, const PhaseSpec& ph);
  PhaseSinks make_sinks() {
    return {tracker_, phase_peaks_, history_,
            wall_start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(opts_.run.max_wall_time_s))};
  }
  PhaseOutcome solve_dynamic(const PhaseModel& phase, const double* q0, const double* qdot0);
  void account(const PhaseOutcome& o, const StageSpec& s, const PhaseSpec& ph);
  // Free stack (stages/free_stack.hpp): the same loop with n-frame phases and impacts.
  void start_free_stage(const StageSpec& s);
  void run_free_phase(const StageSpec& s, const PhaseSpec& ph);
  void fail_free_stop(const StageSpec& s, const PhaseSpec& ph, const PhaseOutcome& o);
  void end_free_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, BayResult& br);
  void fail_phase(const PhaseOutcome& o, int m);
  void end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, BayResult& br);
  void close_stage(BayResult& br);
  void finish();
  void check_accuracy();
  double calc_creep_speed_m_per_s() const {
    if (opts_.drive.mode == DriveMode::motor) return DynamicPhaseSolver::calc_creep_speed_m_per_s(opts_.drive);
    const double peak = tracker_.run[kSpeed].value;
    return DynamicPhaseSolver::kCreepSpeedFraction * std::max(std::abs(u_), std::isfinite(peak) ? peak : 0.0);
  }
  void fail(RunStatus st, std::string msg) { r_.status = st; r_.message = std::move(msg); failed_ = true; }
  void book(double loss_J, double work_J) { ledger_.add_loss(loss_J); ledger_.add_impulse_work(work_J); }
  bool book_contacts(const FreeSegmentStart& c, const StageSpec& s) {  // stack contacts: counts, losses, screw work
    r_.contact_lift_offs += c.lift_offs;
    r_.contact_landings += c.landings;
    r_.contact_energy_loss_J += c.energy_loss_J;
    book(c.energy_loss_J, c.drive_work_J);
    if (!c.ok) fail(RunStatus::singular_configuration, fmt::format("singular configuration: the landing of frame {} at t = {:.9g} s "
                                                                   "(stage of bay {}) has no plastic solution", c.bay, t_, s.bay));
    return c.ok;
  }

  const MastParams& mast_;
  const std::vector<StageSpec>& stages_;
  const RunnerOptions& opts_;
  const double dir_;
  const bool kinematic_;
  const std::chrono::steady_clock::time_point wall_start_;
  RunResult r_;
  EnergyLedger ledger_;
  PeakTracker tracker_;
  PhasePeaks phase_peaks_;
  HistoryRecorder history_;
  std::unique_ptr<integrators::Integrator> integrator_;  // the run's one integrator (time stepping)
  std::unique_ptr<FreeStack> free_;                       // free stack only
  double rail_top_time_s_ = kNaN;                         // free: the hinge rose above y_r (this stage)
  double t_ = 0.0;
  double u_ = 0.0;           // driven-frame velocity carried between stages
  double xi_ = 0.0;          // hinge speed carried between phases
  long evals_ = 0;
  long steps_left_ = 0;
  PhasePoint last_;          // last evaluated point of the run
  const StageSpec* last_stage_ = nullptr;
  const PhaseSpec* last_phase_ = nullptr;
  bool failed_ = false;
  double ke_end_ = 0.0;
};

StageLoop::StageLoop(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts)
    : mast_(mast), stages_(stages), opts_(opts), dir_(calc_direction_sign(opts.run.direction)),
      kinematic_(opts.drive.mode == DriveMode::velocity), wall_start_(std::chrono::steady_clock::now()),
      ledger_(mast), history_(&r_.history, opts.run.output_step_s, opts_.drive, opts.run.max_history_rows), steps_left_(opts.run.max_steps) {
  const int n = mast.n_bays();
  r_.n_bays = n;
  r_.direction = to_string(opts.run.direction);
  r_.drive_mode = to_string(opts.drive.mode);
  r_.bays.resize(static_cast<std::size_t>(n));
  for (int i = 1; i <= n; ++i) r_.bays[static_cast<std::size_t>(i - 1)].bay = i;
  if (!stages.empty() && stages.front().free_stack) {
    free_ = std::make_unique<FreeStack>(mast, stages.front().contacts);
    history_.enable_frames(n + 1);
    if (dir_ < 0) free_->init_deployed();
  }
  if (!kinematic_ || free_) integrator_ = integrators::make_integrator(opts.run.integrator, opts.calc_integrator_options());
  if (kinematic_) r_.motor_torque_at_speed_Nm = opts.drive.calc_motor_torque_Nm(opts.drive.speed_m_per_s);
}

void StageLoop::start_stage(const StageSpec& s, BayResult& br) {
  if (free_) return start_free_stage(s);
  const int m = s.bay;
  const double v = opts_.drive.speed_m_per_s;
  if (s.start == StageStart::from_rest_or_kick && kinematic_) {
    // Impulsive start of the driven part from rest (docs/model.md §4): a lossless ramp of the drive.
    const PhasePoint p0 = HeldPhase(make_context(s, PhaseKind::open, 0.0)).calc_point(s.phases[0].q_start, dir_ * v);
    ++evals_;
    u_ = dir_ * v;
    const DriveRamp ramp = calc_drive_ramp(p0.mass_yy, u_);
    r_.start_drive_impulse_Ns = ramp.impulse_Ns;
    ledger_.add_impulse_work(ramp.work_J);
  }
  if (s.start != StageStart::unlock) return;
  const PhasePoint p0 = HeldPhase(make_context(s, PhaseKind::on_rail, 0.0)).calc_point(0.0, 0.0);
  ++evals_;
  if (kinematic_ && m == stages_.front().bay) {
    // The mast starts from rest: the drive ramps the driven frame and, through the rail, the
    // hinge (x' = -u / c) up together, lossless; no impact, so no latch energy (docs/model.md §2 charges
    // it for the unlock of a moving mast only). Mass along the constrained motion, with
    // M_yx = 0 at x = 0: M_yy + M_xx / c^2.
    const double c = mast_.rail.cot_beta();
    u_ = dir_ * v;
    xi_ = -u_ / c;
    const DriveRamp ramp = calc_drive_ramp(p0.mass_yy + p0.mass_xx / (c * c), u_);
    r_.start_drive_impulse_Ns = ramp.impulse_Ns;
    ledger_.add_impulse_work(ramp.work_J);
    br.unlock_impulse_Ns = calc_pin_force_N(mast_.rail, p0.mass_xx * xi_ / c);  // the rail gives the hinge M_xx xi = c Lambda
    br.latch_energy_J = 0.0;
    br.lock_time_s = t_;
    return;
  }
  const UnlockImpact imp = calc_unlock_impact(p0.mass_yy, p0.mass_xx, mast_.rail.cot_beta(), u_, kinematic_);
  if (kinematic_) ledger_.add_impulse_work(imp.drive_work_J);
  else u_ += imp.du_m_per_s;
  xi_ = imp.hinge_speed_m_per_s;
  br.unlock_impulse_Ns = calc_pin_force_N(mast_.rail, imp.rail_impulse_Ns);  // per pin, as the force
  br.latch_energy_J = imp.energy_loss_J;
  br.lock_time_s = t_;
  ledger_.add_loss(imp.energy_loss_J);
}

void StageLoop::fail_phase(const PhaseOutcome& o, int m) {
  const char* goal = dir_ > 0 ? "lock" : "end";
  switch (o.reason) {
    case PhaseEndReason::reached_end: return;
    case PhaseEndReason::model_stop: return;  // the free stack's stop events: fail_free_stop
    case PhaseEndReason::cannot_start:
      return fail(RunStatus::stall, fmt::format("stall: the drive cannot move the mast at t = {:.9g} s in the stage of bay {} "
                                                "(drive force {:.6g} N)", t_, m, o.end.drive_force_N));
    case PhaseEndReason::crept_to_rest:
      return fail(RunStatus::stall, fmt::format("stall: the driven frame crept to rest (speed below {:.3g} m/s) at y = {:.9g} m, "
                                                "t = {:.9g} s, in the stage of bay {} before its {}: the {} balances the mast "
                                                "short of the {}",
                                                calc_creep_speed_m_per_s(), o.end.y_driven_m, t_, m, goal,
                                                opts_.drive.mode == DriveMode::motor ? "motor's stall torque" : "drive torque", goal));
    case PhaseEndReason::stopped:
      return fail(RunStatus::stall, fmt::format("stall: the driven frame stopped at y = {:.9g} m, t = {:.9g} s, in the stage "
                                                "of bay {} before its {}", o.end.y_driven_m, t_, m, goal));
    case PhaseEndReason::wall_time:
      return fail(RunStatus::wall_time_limit, fmt::format("wall-time cap of {} s reached at t = {:.9g} s (bay {})",
                                                          opts_.run.max_wall_time_s, t_, m));
    case PhaseEndReason::horizon:
      return fail(RunStatus::stall, fmt::format("stall: the stage of bay {} has not reached its {} after {:.3g} s of simulated "
                                                "time (t = {:.9g} s); the driven frame creeps at {:.3g} m/s",
                                                m, goal, DynamicPhaseSolver::kHorizon_s, t_, o.end.u_m_per_s));
    case PhaseEndReason::step_limit:
      return fail(RunStatus::step_limit, fmt::format("step cap of {} steps reached at t = {:.9g} s (bay {})",
                                                     opts_.run.max_steps, t_, m));
    case PhaseEndReason::failure:
      return fail(RunStatus::solver_failure, fmt::format("integrator failure at t = {:.9g} s (bay {}): {}", t_, m, o.message));
  }
}

void StageLoop::run_phase(const StageSpec& s, const PhaseSpec& ph) {
  if (free_) return run_free_phase(s, ph);
  PhaseContext ctx = make_context(s, ph.kind, ph.lower_held_height_m);
  ctx.q_end = ph.q_end;
  ctx.sign_q = ph.q_end > ph.q_start ? 1.0 : -1.0;
  const HeldPhase phase(ctx);
  const double q0 = ph.q_start, qdot0 = ph.kind == PhaseKind::open ? u_ : xi_;
  PhaseSinks sinks = make_sinks();
  PhaseOutcome o;
  if (kinematic_) o = KinematicPhaseSolver(phase, ph, opts_.peak_samples_per_piece).solve({t_, &q0, &qdot0}, sinks);
  else o = solve_dynamic(phase, &q0, &qdot0);
  account(o, s, ph);
  fail_phase(o, s.bay);
}

PhaseOutcome StageLoop::solve_dynamic(const PhaseModel& phase, const double* q0, const double* qdot0) {
  PhaseSinks sinks = make_sinks();
  integrators::IntegratorOptions io = opts_.calc_integrator_options();
  io.max_steps = std::max(1L, steps_left_);
  return DynamicPhaseSolver(phase, *integrator_, io).solve({t_, q0, qdot0, calc_creep_speed_m_per_s()}, sinks);
}

void StageLoop::account(const PhaseOutcome& o, const StageSpec& s, const PhaseSpec& ph) {
  steps_left_ -= o.steps;
  r_.steps += o.steps;
  r_.rejected_steps += o.rejected_steps;
  evals_ += o.evals;
  if (o.reason != PhaseEndReason::cannot_start) ledger_.add_smooth_work(o.drive_work_J);
  t_ = o.t_end_s;
  last_ = o.end; last_stage_ = &s; last_phase_ = &ph;
}

void StageLoop::end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, BayResult& br) {
  if (free_) return end_free_phase(s, ph, p_end, br);
  const double u_end = p_end.u_m_per_s;
  switch (ph.end) {
    case PhaseEnd::rail_entry: {
      // Plastic impact of the held lower frame with the rail (docs/model.md §2), in frame heights.
      const TwoFrameMass M = calc_two_frame_mass(mast_, s.bay, s.locked_mass_kg, s.panel_height_offset_m, ph.lower_held_height_m, p_end.y_driven_m);
      const double x = s.entry_hinge_x_m, D = p_end.y_driven_m - ph.lower_held_height_m;
      const FrameImpact imp = calc_rail_entry_impact(M, calc_rail_gradient(mast_.rail.cot_beta(), D, x), u_end, kinematic_);
      u_ = u_end + imp.du_m_per_s;
      xi_ = u_ / calc_on_rail(mast_.rail, mast_.bay(s.bay).strut_length_m, x).dY;
      br.entry_time_s = t_;
      br.entry_impulse_Ns = calc_pin_force_N(mast_.rail, imp.rail_impulse_Ns);  // per pin, as the force
      br.entry_drive_impulse_Ns = imp.drive_impulse_Ns;
      br.entry_energy_loss_J = imp.energy_loss_J;
      book(imp.energy_loss_J, imp.drive_work_J);
      break;
    }
    case PhaseEnd::lock: {
      // The latch stops the struts' radial motion: g(0) xi^2 is lost; y_m' is continuous.
      const double loss = calc_latch_loss_J(p_end.mass_xx, p_end.qdot);
      br.lock_time_s = t_;
      br.latch_energy_J = loss;
      ledger_.add_loss(loss);
      u_ = u_end;
      ke_end_ = p_end.kinetic_energy_J - loss;
      ++r_.bays_completed;
      break;
    }
    case PhaseEnd::rail_exit: {
      // The lower frame lands on the stack: plastic, its velocity w -> 0.
      const TwoFrameMass M = calc_two_frame_mass(mast_, s.bay, s.locked_mass_kg, s.panel_height_offset_m, p_end.y_lower_m, p_end.y_driven_m);
      const FrameImpact imp = calc_rail_exit_impact(M, p_end.w_m_per_s, u_end, kinematic_);
      u_ = u_end + imp.du_m_per_s;
      br.entry_time_s = t_;
      br.landing_impulse_Ns = std::abs(imp.stack_impulse_Ns);
      br.entry_impulse_Ns = 0.0;  // the pin leaves the rail: no rail impulse
      br.entry_drive_impulse_Ns = imp.drive_impulse_Ns;
      br.entry_energy_loss_J = imp.energy_loss_J;
      book(imp.energy_loss_J, imp.drive_work_J);
      break;
    }
    case PhaseEnd::reach_height: {
      u_ = u_end;
      ++r_.bays_completed;
      if (s.final_landing) {
        // Frame n lands on the stack: the whole (stowed) mast stops, plastic.
        ledger_.add_loss(p_end.kinetic_energy_J);
        ke_end_ = 0.0;
        u_ = 0.0;
      } else {
        ke_end_ = p_end.kinetic_energy_J;
      }
      break;
    }
  }
}

void StageLoop::start_free_stage(const StageSpec& s) {
  rail_top_time_s_ = kNaN;
  free_->start_stage(s.bay);
  if (s.start == StageStart::unlock) {  // retraction: unlock of bay m with every moving frame (docs/model.md §2)
    const bool from_rest = &s == &stages_.front();
    const FreeContactEvent e = free_->apply_unlock(make_context(s, PhaseKind::on_rail, 0.0), dir_ * opts_.drive.speed_m_per_s, kinematic_, from_rest);
    if (!e.ok) return fail(RunStatus::singular_configuration, fmt::format("singular configuration: the unlock of bay {} has no solution", s.bay));
    if (from_rest && kinematic_) r_.start_drive_impulse_Ns = e.impulse_Ns;
    r_.bays[static_cast<std::size_t>(s.bay - 1)].latch_energy_J = e.energy_loss_J;
    r_.bays[static_cast<std::size_t>(s.bay - 1)].lock_time_s = t_;
    return book(e.energy_loss_J, e.drive_work_J);
  }
  if (s.start != StageStart::from_rest_or_kick || !kinematic_) return;
  // Impulsive start (docs/model.md §2 "free"): the free frames take the momentum-consistent kick.
  const StackImpact k = free_->apply_start_kick(s, dir_ * opts_.drive.speed_m_per_s);
  if (!k.ok) return fail(RunStatus::singular_configuration, "singular configuration: the stowed stack's mass matrix is not positive definite");
  r_.start_drive_impulse_Ns = k.drive_impulse_Ns;
  ledger_.add_impulse_work(k.drive_work_J);
}

void StageLoop::run_free_phase(const StageSpec& s, const PhaseSpec& ph) {
  PhaseContext ctx = make_context(s, ph.kind, 0.0);
  ctx.q_end = dir_ > 0 ? 0.0 : ph.q_end;  // on the rail: the lock at x = 0 (x falling), or the exit
  ctx.sign_q = ph.kind == PhaseKind::on_rail ? -dir_ : dir_;
  // Watched events of the open phase, each at most once: the rail-top crossing (recorded) and the
  // first minimum of f (a grazing entry if f <= 0 there, else the phase goes on).
  bool watch = ph.kind == PhaseKind::open && dir_ > 0, watch_min = watch;
  for (;;) {
    if (!book_contacts(free_->prepare_segment(ctx, kinematic_), s)) return;  // open the pulling, land the touching
    const std::unique_ptr<PhaseModel> phase = free_->make_phase(ctx, watch, watch_min);
    std::vector<double> q0, qd0;
    free_->get_start(ctx, q0, qd0);
    const PhaseOutcome o = solve_dynamic(*phase, q0.data(), qd0.data());
    account(o, s, ph);
    if (!o.end_state.empty()) free_->set_end(ctx, o.end_state);
    if (o.reason == PhaseEndReason::model_stop) {  // stack contacts: a landing or a lift-off, then on
      const FreeSegmentStart c = free_->apply_contact_event(ctx, o.stop_event, kinematic_);
      if (c.handled && !book_contacts(c, s)) return;
      if (c.handled) continue;
    }
    if (o.reason == PhaseEndReason::model_stop && watch && o.stop_event == FreePhaseA::above_rail_top) {
      rail_top_time_s_ = t_;  // recorded; the phase goes on without this event
      watch = false;
      continue;
    }
    if (o.reason == PhaseEndReason::model_stop && watch_min && o.stop_event == FreePhaseA::rail_approach_min) {
      // f' = 0 with f <= 0: the pin dipped into the rail within a step; it enters here, where its
      // velocity is tangent to the rail (f' = 0: the entry impulse vanishes with the dip).
      if (free_->calc_rail_function_m(s.bay) <= 0.0) return;
      watch_min = false;
      continue;
    }
    if (o.reason == PhaseEndReason::model_stop) return fail_free_stop(s, ph, o);
    return fail_phase(o, s.bay);
  }
}

void StageLoop::fail_free_stop(const StageSpec& s, const PhaseSpec& ph, const PhaseOutcome& o) {
  const int m = s.bay;
  if (ph.kind == PhaseKind::on_rail || o.stop_event == FreePhaseA::singular_bay)
    return fail(RunStatus::singular_configuration, free_->describe_singular(m, t_));
  const Extremum& a = tracker_.stage_rail_approach;
  r_.rail_miss_bay = m;
  r_.rail_miss_closest_approach_m = -a.value;
  r_.rail_miss_closest_approach_time_s = a.t;
  r_.rail_miss_above_rail_top_time_s = rail_top_time_s_;
  fail(RunStatus::rail_miss, free_->describe_rail_miss(m, o.stop_event == FreePhaseA::past_miss_height, -a.value, a.t, rail_top_time_s_, t_));
}

void StageLoop::end_free_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, BayResult& br) {
  if (ph.end == PhaseEnd::rail_exit) {  // retraction: frame m-1 lands on the floor or the resting stack
    const FreeContactEvent e = free_->apply_rail_exit(s, kinematic_);
    if (!e.ok) return fail(RunStatus::singular_configuration, fmt::format("singular configuration: the rail exit of bay {} has no solution", s.bay));
    br.entry_time_s = t_;
    br.landing_impulse_Ns = std::abs(e.impulse_Ns);
    br.entry_impulse_Ns = br.entry_drive_impulse_Ns = 0.0;
    br.entry_energy_loss_J = e.energy_loss_J;
    book(e.energy_loss_J, e.drive_work_J);
    return;
  }
  if (ph.end == PhaseEnd::reach_height) {  // retraction: frame m back at its deployment start height
    ++r_.bays_completed;
    ke_end_ = s.final_landing ? 0.0 : p_end.kinetic_energy_J;
    if (s.final_landing) ledger_.add_loss(p_end.kinetic_energy_J);  // the whole stack stops on the floor
    return;
  }
  if (ph.end == PhaseEnd::rail_entry) {
    // Plastic impact of all moving frames with the rail (model/free_impacts.hpp).
    const FreeRailEntry e = free_->apply_rail_entry(s, kinematic_);
    if (!e.impact.ok) return fail(RunStatus::singular_configuration,
                                  fmt::format("singular configuration: the rail entry of bay {} at t = {:.9g} s has no solution", s.bay, t_));
    br.entry_time_s = t_;
    br.entry_impulse_Ns = calc_pin_force_N(mast_.rail, e.impact.rail_impulse_Ns);  // per pin, as the force
    br.entry_drive_impulse_Ns = e.impact.drive_impulse_Ns;
    br.entry_energy_loss_J = e.impact.energy_loss_J;
    book(e.impact.energy_loss_J, e.impact.drive_work_J);
    return;
  }
  // Lock: the latch stops the struts' radial motion, g(0) xi^2 is lost; y_m' is continuous.
  const double loss = calc_latch_loss_J(p_end.mass_xx, p_end.qdot);
  free_->apply_lock(s.bay);
  br.lock_time_s = t_;
  br.latch_energy_J = loss;
  ledger_.add_loss(loss);
  ke_end_ = p_end.kinetic_energy_J - loss;
  ++r_.bays_completed;
}

void StageLoop::close_stage(BayResult& br) {
  br.peak_drive_force_N = std::isfinite(tracker_.stage_force.value) ? tracker_.stage_force.value : kNaN;
  br.peak_drive_force_time_s = tracker_.stage_force.t;
  br.peak_pin_force_N = std::isfinite(tracker_.stage_pin.value) ? tracker_.stage_pin.value : kNaN;
  br.peak_pin_force_time_s = tracker_.stage_pin.t;
  tracker_.close_stage();
}

void StageLoop::finish() {
  r_.end_time_s = t_;
  if (failed_) {
    ke_end_ = last_.kinetic_energy_J;
  } else {
    r_.deploy_time_s = t_;
  }
  if (free_ && history_.records_frames() && last_stage_) free_->get_frame_heights(last_stage_->bay, history_.frame_buffer());
  history_.finish(t_, last_, last_stage_ ? last_stage_->bay : 0);
  auto fin = [](double v) { return std::isfinite(v) ? v : kNaN; };
  const auto& run = tracker_.run;
  r_.peak_drive_force_N = fin(run[kForce].value);
  r_.peak_drive_force_time_s = run[kForce].t;
  r_.peak_drive_force_bay = run[kForce].bay;
  r_.min_drive_force_N = fin(-run[kNegForce].value);
  r_.min_drive_force_time_s = run[kNegForce].t;
  r_.min_drive_force_bay = run[kNegForce].bay;
  r_.peak_drive_torque_Nm = opts_.drive.calc_torque_Nm(r_.peak_drive_force_N);
  r_.min_drive_torque_Nm = opts_.drive.calc_torque_Nm(r_.min_drive_force_N);
  r_.peak_static_drive_torque_Nm = opts_.drive.calc_torque_Nm(fin(run[kStaticForce].value)) + 0.0;  // + 0: no -0
  r_.peak_inertial_drive_torque_Nm = opts_.drive.calc_torque_Nm(fin(run[kInertialForce].value)) + 0.0;
  r_.peak_pin_force_N = fin(run[kPin].value);
  r_.peak_pin_force_time_s = run[kPin].t;
  r_.peak_pin_force_bay = run[kPin].bay;
  r_.peak_diagonal_tension_N = fin(run[kTension].value);
  for (const auto& b : r_.bays)
    if (std::isfinite(b.latch_energy_J) && !(b.latch_energy_J <= r_.peak_latch_energy_J)) r_.peak_latch_energy_J = b.latch_energy_J;
  r_.peak_driven_speed_m_per_s = fin(run[kSpeed].value);
  r_.max_rail_residual_m = tracker_.max_rail_residual;
  if (std::isfinite(run[kOverlap].value)) {
    r_.min_bay_opening_m = -run[kOverlap].value;
    r_.min_bay_opening_time_s = run[kOverlap].t;
    r_.min_bay_opening_bay = run[kOverlap].bay;
  }

  const double U_start = dir_ > 0 ? ledger_.get_stowed_potential_J() : ledger_.get_deployed_potential_J();
  double U_end = 0.0;
  if (last_stage_ && last_phase_) {
    // The free stack's phases carry every bay below the driven frame.
    const int first_moving = free_ ? std::max(free_->get_last_lowest_frame(), 1) : last_phase_->kind == PhaseKind::on_rail ? std::max(last_stage_->bay - 1, 1) : last_stage_->bay;
    if (failed_) U_end = ledger_.calc_total_potential_J(last_stage_->bay, first_moving, last_.potential_energy_J);
    else if (free_ && dir_ < 0) U_end = free_->calc_potential_energy_J();  // the free frames need not end stowed
    else U_end = dir_ > 0 ? ledger_.get_deployed_potential_J() : ledger_.get_stowed_potential_J();
  }
  ledger_.set_start(0.0, U_start);
  ledger_.set_end(ke_end_, U_end);
  ledger_.fill(r_);
  check_accuracy();
  r_.rhs_evals = evals_;
  r_.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
}

// An `ok` run promises finite numbers and an energy balance within its tolerance (energy.hpp).
void StageLoop::check_accuracy() {
  if (failed_) return;
  std::string why = calc_accuracy_failure(r_, opts_.run.rtol, opts_.run.atol, mast_.bay(1).strut_length_m);
  if (!why.empty()) fail(RunStatus::inaccurate, std::move(why));
}

RunResult StageLoop::run() {
  for (const StageSpec& s : stages_) {
    if (failed_) break;
    BayResult& br = r_.bays[static_cast<std::size_t>(s.bay - 1)];
    tracker_.start_stage(s.bay);
    start_stage(s, br);
    for (std::size_t ip = 0; ip < s.phases.size() && !failed_; ++ip) {
      run_phase(s, s.phases[ip]);
      if (!failed_) end_phase(s, s.phases[ip], last_, br);
    }
    close_stage(br);
  }
  if (failed_) {
    // partial stage: its peaks so far still count
    tracker_.close_stage();
    if (tracker_.bay > 0) {
      BayResult& br = r_.bays[static_cast<std::size_t>(tracker_.bay - 1)];
      if (std::isfinite(tracker_.stage_force.value)) { br.peak_drive_force_N = tracker_.stage_force.value; br.peak_drive_force_time_s = tracker_.stage_force.t; }
      if (std::isfinite(tracker_.stage_pin.value)) { br.peak_pin_force_N = tracker_.stage_pin.value; br.peak_pin_force_time_s = tracker_.stage_pin.t; }
    }
  }
  finish();
  return std::move(r_);
}

}  // namespace

RunResult run_stages(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts) {
  if (std::string e = opts.validate(); !e.empty()) {
    RunResult r;
    r.status = RunStatus::invalid_input;
    r.message = std::move(e);
    r.n_bays = mast.n_bays();
    return r;
  }
  return StageLoop(mast, stages, opts).run();
}

}  // namespace truss::stages
