// A stack mode as the one stage loop (stage_loop.hpp) sees it (docs/model.md §2): the state of the
// moving frames between phases, the phase models with the solver that runs each (phase_solver.hpp),
// and the events at the stage and phase boundaries. A stack mode computes an event; the stage loop
// books every event the same way (energy ledger, bay record, status). The held stack
// (held_stack.hpp) runs a phase in one segment; the free stack (free_stack_model.hpp) in segments
// between its stack-contact and watched events. A further stack mode is one more StackModel.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "integrators/ode.hpp"
#include "model/params.hpp"
#include "stages/peaks.hpp"
#include "stages/phase_solver.hpp"
#include "stages/result.hpp"
#include "stages/run_options.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

// An event at a stage or phase boundary (start ramp, unlock, rail entry, rail exit, lock) or at
// the start or stop of a segment (stack contacts), as a stack mode computes it.
struct StackEvent {
  std::string failure;                   // not empty: the event has no solution (singular configuration)
  double start_drive_impulse_Ns = kNaN;  // a start from rest: the drive's ramp impulse (N s); NaN: none
  double rail_impulse_Ns = kNaN;         // the rail's impulse on the pins together (N s); NaN: not reported
  double drive_impulse_Ns = kNaN;        // the screw's impulse (N s)
  double landing_impulse_Ns = kNaN;      // the stack's impulse on a landing frame (N s)
  double energy_loss_J = 0;              // lost in the impact(s)
  double drive_work_J = 0;               // work of the drive's impulse(s)
  long contact_landings = 0, contact_lift_offs = 0;  // stack contacts
  long evals = 0;                        // model evaluations the event took
  double rail_margin_m = kNaN;           // a free-stack rail entry: its margin (RunResult::rail_margin_m)
};

// A stretch of a phase that one solver runs: its solver (owned by the stack mode, valid until the
// next segment; null when the segment's start events failed) and the start state of its model.
struct PhaseSegment {
  StackEvent start_events;  // stack contacts opened or landed before the segment
  PhaseSolver* solver = nullptr;
  const double* q = nullptr;
  const double* qdot = nullptr;
  // Torque mode: a speed (m/s) the creep test takes as a reference besides the run's peak speed so
  // far (the held stack: the driven frame's speed at the phase start).
  double creep_reference_m_per_s = 0;
};

// What follows a segment's end, as the stack mode reads the outcome.
struct SegmentEnd {
  enum class Next {
    by_outcome,    // the outcome's reason decides: reached_end ends the phase, the others fail the run
    next_segment,  // a stop event handled (contact, watched crossing): the phase goes on
    failed,        // a stop rule of the model (rail miss, singular configuration): status, message
  };
  Next next = Next::by_outcome;
  StackEvent event;             // the stop event's impacts (contact landing)
  RunStatus status = RunStatus::ok;
  std::string message;
  double above_rail_top_time_s = kNaN;  // rail miss: when the hinge rose above the rail's top (NaN: never)
};

class StackModel {
 public:
  virtual ~StackModel() = default;
  // The stage's start event: an impulsive start of the drive from rest, or the unlock of bay s.bay.
  virtual StackEvent start_stage(const StageSpec& s, bool first_stage) = 0;
  // The next segment of phase ph of stage s at time t_s (first: the phase's first segment); io: the
  // integrator options with the run's remaining step budget.
  virtual PhaseSegment begin_segment(const StageSpec& s, const PhaseSpec& ph, bool first, double t_s,
                                     const integrators::IntegratorOptions& io) = 0;
  // The segment ended at t_s with outcome o; closest: the stage's closest approach of the hinge to
  // the rail so far (for a rail miss's message).
  virtual SegmentEnd end_segment(const PhaseOutcome& o, double t_s, const Extremum& closest) = 0;
  // The impact or state change that ends phase ph at p_end (rail entry, lock, rail exit, height).
  virtual StackEvent end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, double t_s) = 0;
  // The lowest frame the last phase moved (the bays below it are stowed), for a run's potential energy.
  virtual int find_first_moving_frame(const StageSpec& s, const PhaseSpec& ph) const = 0;
  // Potential energy of the whole mast at the end of a completed run (J); the stowed or deployed
  // mast's unless the stack mode knows better.
  virtual double calc_end_potential_J(double stowed_J, double deployed_J) const {
    return dir_ > 0 ? deployed_J : stowed_J;
  }
  // Frames the history records per row (0: none), and their heights with driven frame m.
  virtual int count_history_frames() const { return 0; }
  virtual void get_frame_heights(int /*m*/, double* /*y*/) const {}

 protected:
  StackModel(const model::MastParams& mast, const RunnerOptions& opts)
      : mast_(mast), opts_(opts), dir_(model::calc_direction_sign(opts.run.direction)),
        drive_holds_speed_(opts.drive.mode == model::DriveMode::velocity) {}
  PhaseContext make_context(const StageSpec& s, PhaseKind kind, double lower_held_height_m) const {
    return {&mast_, kind, s.bay, lower_held_height_m, s.locked_mass_kg, s.panel_height_offset_m, opts_.drive, dir_,
            0.0, 1.0};
  }
  const model::MastParams& mast_;
  const RunnerOptions& opts_;
  const double dir_;
  const bool drive_holds_speed_;  // velocity drive: the screw keeps the driven frame's speed
};

}  // namespace truss::stages
