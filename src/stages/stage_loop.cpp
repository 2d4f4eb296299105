#include "stages/stage_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "model/impacts.hpp"
#include "model/motorisation.hpp"
#include "model/rail.hpp"
#include "stages/energy.hpp"
#include "stages/phase_dynamic.hpp"

namespace truss::stages {

using namespace truss::model;

namespace {

class StageLoop {
 public:
  StageLoop(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts,
            std::unique_ptr<StackModel> stack);
  RunResult run();

 private:
  void start_stage(const StageSpec& s, BayResult& br);
  void run_phase(const StageSpec& s, const PhaseSpec& ph);
  void end_phase(const StageSpec& s, const PhaseSpec& ph, BayResult& br);
  PhaseSinks make_sinks() {
    return {tracker_, phase_peaks_, history_,
            wall_start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(opts_.run.max_wall_time_s)),
            segments_++ % PhaseSinks::kClockEvery == 0, &clock_work_};
  }
  void account(const PhaseOutcome& o, const StageSpec& s, const PhaseSpec& ph);
  bool book(const StackEvent& e);
  void fail_phase(const PhaseOutcome& o, int m);
  void fail_stop(const SegmentEnd& e, int m);
  void close_stage(BayResult& br);
  void finish();
  void fill_motor_torques();
  void check_accuracy();
  double calc_creep_speed_m_per_s() const {
    if (opts_.drive.mode == DriveMode::motor) return DynamicPhaseSolver::calc_creep_speed_m_per_s(opts_.drive);
    const double peak = tracker_.run[kSpeed].value;
    return DynamicPhaseSolver::kCreepSpeedFraction * std::max(creep_reference_m_per_s_, std::isfinite(peak) ? peak : 0.0);
  }
  void fail(RunStatus st, std::string msg) { r_.status = st; r_.message = std::move(msg); failed_ = true; }

  const MastParams& mast_;
  const std::vector<StageSpec>& stages_;
  const RunnerOptions& opts_;
  const double dir_;
  const std::chrono::steady_clock::time_point wall_start_;
  RunResult r_;
  EnergyLedger ledger_;
  PeakTracker tracker_;
  PhasePeaks phase_peaks_;
  HistoryRecorder history_;
  std::unique_ptr<StackModel> stack_;  // the plan's stack mode
  double t_ = 0.0;
  double creep_reference_m_per_s_ = 0.0;  // the segment's (PhaseSegment)
  long evals_ = 0;
  long steps_left_ = 0;
  long segments_ = 0;  // phase segments begun (PhaseSinks::check_clock)
  long clock_work_ = 0;  // PhaseSinks::clock_work
  PhasePoint last_;          // last evaluated point of the run
  const StageSpec* last_stage_ = nullptr;
  const PhaseSpec* last_phase_ = nullptr;
  bool failed_ = false;
  double ke_end_ = 0.0;
};

StageLoop::StageLoop(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts,
                     std::unique_ptr<StackModel> stack)
    : mast_(mast), stages_(stages), opts_(opts), dir_(calc_direction_sign(opts.run.direction)),
      wall_start_(opts.wall_start == std::chrono::steady_clock::time_point{} ? std::chrono::steady_clock::now() : opts.wall_start),
      ledger_(mast),
      history_(&r_.history, opts.run.output_step_s, opts_.drive, opts.run.max_history_bytes),
      stack_(std::move(stack)), steps_left_(opts.run.max_steps) {
  const int n = mast.n_bays();
  r_.n_bays = n;
  r_.direction = to_string(opts.run.direction);
  r_.drive_mode = to_string(opts.drive.mode);
  r_.bays.resize(static_cast<std::size_t>(n));
  for (int i = 1; i <= n; ++i) r_.bays[static_cast<std::size_t>(i - 1)].bay = i;
  history_.enable_frames(stack_->count_history_frames());
  // Peaks equal to the run's accuracy are one peak, reported where it first occurs (peaks.hpp).
  const double tie = calc_allowed_relative_error(n, opts.run.rtol, opts.run.atol, mast.bay(1).strut_length_m);
  tracker_.set_tie_tolerance(tie);
  phase_peaks_.set_tie_tolerance(tie);
  if (opts.drive.mode == DriveMode::velocity) r_.motor_torque_at_speed_Nm = opts.drive.calc_motor_torque_Nm(opts.drive.speed_m_per_s);
}

// Books an event of the stack mode: its losses and impulse work, its contacts; false (and the run
// fails) when it has no solution.
bool StageLoop::book(const StackEvent& e) {
  evals_ += e.evals;
  r_.contact_lift_offs += e.contact_lift_offs;
  r_.contact_landings += e.contact_landings;
  if (e.contact_landings > 0) r_.contact_energy_loss_J += e.energy_loss_J;
  if (!std::isnan(e.rail_margin_m) && !(r_.rail_margin_m <= e.rail_margin_m)) r_.rail_margin_m = e.rail_margin_m;
  ledger_.add_loss(e.energy_loss_J);
  ledger_.add_impulse_work(e.drive_work_J);
  if (!e.failure.empty()) fail(RunStatus::singular_configuration, e.failure);
  return e.failure.empty();
}

void StageLoop::start_stage(const StageSpec& s, BayResult& br) {
  const StackEvent e = stack_->start_stage(s, &s == &stages_.front());
  if (!book(e)) return;
  if (std::isfinite(e.start_drive_impulse_Ns)) r_.start_drive_impulse_Ns = e.start_drive_impulse_Ns;
  if (s.start != StageStart::unlock) return;
  br.unlock_impulse_Ns = calc_pin_force_N(mast_.rail, e.rail_impulse_Ns);  // per pin, as the force
  br.latch_energy_J = e.energy_loss_J;
  br.lock_time_s = t_;
}

void StageLoop::fail_phase(const PhaseOutcome& o, int m) {
  const char* goal = dir_ > 0 ? "lock" : "end";
  switch (o.reason) {
    case PhaseEndReason::reached_end: return;
    case PhaseEndReason::model_stop: return;  // the stack mode's stop events: fail_stop
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

// A stop rule of the stack mode's model; a rail miss keeps the stage's closest approach.
void StageLoop::fail_stop(const SegmentEnd& e, int m) {
  if (e.status == RunStatus::rail_miss) {
    const Extremum& a = tracker_.stage_rail_approach;
    r_.rail_miss_bay = m;
    r_.rail_miss_closest_approach_m = -a.value;
    r_.rail_miss_closest_approach_time_s = a.t;
    r_.rail_miss_above_rail_top_time_s = e.above_rail_top_time_s;
    r_.rail_margin_m = a.value;  // minus the closest approach
  }
  fail(e.status, e.message);
}

// A phase in the segments its stack mode gives, each through its phase solver.
void StageLoop::run_phase(const StageSpec& s, const PhaseSpec& ph) {
  for (bool first = true;; first = false) {
    integrators::IntegratorOptions io = opts_.calc_integrator_options();
    io.max_steps = std::max(1L, steps_left_);
    const PhaseSegment seg = stack_->begin_segment(s, ph, first, t_, io);
    if (!book(seg.start_events)) return;
    creep_reference_m_per_s_ = seg.creep_reference_m_per_s;
    PhaseSinks sinks = make_sinks();
    if (sinks.check_clock && std::chrono::steady_clock::now() > sinks.deadline) {  // the set-up of the segments
      PhaseOutcome late;
      late.reason = PhaseEndReason::wall_time;
      late.t_end_s = t_;
      late.end = last_;
      return fail_phase(late, s.bay);
    }
    const PhaseOutcome o = seg.solver->solve({t_, seg.q, seg.qdot, calc_creep_speed_m_per_s()}, sinks);
    account(o, s, ph);
    const SegmentEnd e = stack_->end_segment(o, t_, tracker_.stage_rail_approach);
    if (!book(e.event)) return;
    switch (e.next) {
      case SegmentEnd::Next::next_segment: continue;
      case SegmentEnd::Next::failed: return fail_stop(e, s.bay);
      case SegmentEnd::Next::by_outcome: return fail_phase(o, s.bay);
    }
  }
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

// The event that ends a phase, computed by the stack mode, booked here for every stack mode.
void StageLoop::end_phase(const StageSpec& s, const PhaseSpec& ph, BayResult& br) {
  const PhasePoint p = last_;
  const StackEvent e = stack_->end_phase(s, ph, p, t_);
  if (!book(e)) return;
  switch (ph.end) {
    case PhaseEnd::rail_entry:
      br.entry_time_s = t_;
      br.entry_impulse_Ns = calc_pin_force_N(mast_.rail, e.rail_impulse_Ns);  // per pin, as the force
      br.entry_drive_impulse_Ns = e.drive_impulse_Ns;
      br.entry_energy_loss_J = e.energy_loss_J;
      return;
    case PhaseEnd::rail_exit:
      br.entry_time_s = t_;
      br.landing_impulse_Ns = e.landing_impulse_Ns;
      br.entry_impulse_Ns = 0.0;  // the pin leaves the rail: no rail impulse
      br.entry_drive_impulse_Ns = e.drive_impulse_Ns;
      br.entry_energy_loss_J = e.energy_loss_J;
      return;
    case PhaseEnd::lock: {
      // The latch stops the struts' radial motion: g(0) xi^2 is lost; y_m' is continuous.
      const double loss = calc_latch_loss_J(p.mass_xx, p.qdot);
      br.lock_time_s = t_;
      br.latch_energy_J = loss;
      ledger_.add_loss(loss);
      ke_end_ = p.kinetic_energy_J - loss;
      ++r_.bays_completed;
      return;
    }
    case PhaseEnd::reach_height:
      ++r_.bays_completed;
      ke_end_ = s.final_landing ? 0.0 : p.kinetic_energy_J;
      if (s.final_landing) ledger_.add_loss(p.kinetic_energy_J);  // frame n lands on the stack: the whole mast stops
      return;
  }
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
  if (history_.records_frames() && last_stage_) stack_->get_frame_heights(last_stage_->bay, history_.frame_buffer());
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
  fill_motor_torques();
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
    const int first_moving = stack_->find_first_moving_frame(*last_stage_, *last_phase_);
    if (failed_) U_end = ledger_.calc_total_potential_J(last_stage_->bay, first_moving, last_.potential_energy_J);
    else U_end = stack_->calc_end_potential_J(ledger_.get_stowed_potential_J(), ledger_.get_deployed_potential_J());
  }
  ledger_.set_start(0.0, U_start);
  ledger_.set_end(ke_end_, U_end);
  ledger_.fill(r_);
  check_accuracy();
  r_.rhs_evals = evals_;
  r_.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
}

// The torque the motor must give and the motorisation check (model/drive.hpp, model/motorisation.hpp),
// from the peaks: the largest force along the run direction is the peak force deploying and minus
// the minimum retracting; the check's inertial resistance counts where a speed is prescribed. The
// stall margin (velocity mode) drives the peak force along +y through the train: deploying, the
// peak along the run; retracting, the largest holding force taken as one to drive (conservative).
void StageLoop::fill_motor_torques() {
  const model::DriveParams& d = opts_.drive;
  r_.peak_motor_torque_Nm = d.calc_motor_torque_for_force_Nm(dir_ > 0 ? r_.peak_drive_force_N : -r_.min_drive_force_N);
  r_.motor_torque_margin_Nm = r_.motor_torque_at_speed_Nm - d.calc_motor_torque_for_force_Nm(r_.peak_drive_force_N);
  const double inertial = d.mode == DriveMode::velocity ? r_.peak_inertial_drive_torque_Nm : 0.0;
  const model::MotorisationTorques res = model::calc_motorisation_torques(d, r_.peak_static_drive_torque_Nm, inertial);
  r_.motorisation_required_torque_Nm = model::calc_required_torque_Nm(res, opts_.motorisation);
  r_.motorisation_available_torque_Nm = model::calc_available_torque_Nm(d);
  r_.motorisation_margin = model::calc_motorisation_margin(r_.motorisation_available_torque_Nm, r_.motorisation_required_torque_Nm);
  r_.motorisation_stall_torque_Nm = model::calc_needed_stall_torque_Nm(d, r_.motorisation_required_torque_Nm);
}

// An `ok` run promises finite numbers and an energy balance within its tolerance (energy.hpp).
void StageLoop::check_accuracy() {
  if (failed_) return;
  const bool contacts = !stages_.empty() && stages_.front().contacts;
  std::string why = calc_accuracy_failure(r_, opts_.run.rtol, opts_.run.atol, mast_.bay(1).strut_length_m, contacts);
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
      if (!failed_) end_phase(s, s.phases[ip], br);
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

RunResult run_stages(const MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts,
                     std::unique_ptr<StackModel> stack) {
  return StageLoop(mast, stages, opts, std::move(stack)).run();
}

}  // namespace truss::stages
