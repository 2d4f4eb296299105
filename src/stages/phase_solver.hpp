// One interface for the solvers of a phase: a closed-form kinematic solver (velocity drive,
// held stack: y_m is linear in time, no time stepping) and a time-stepping solver (any drive,
// any PhaseModel, through the run's one Integrator). A solver runs the phase from its start
// state to its end event, feeds the peak tracker and the history, and says how the phase ended.
#pragma once
#include <chrono>
#include <string>
#include <vector>

#include "stages/history.hpp"
#include "stages/peaks.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

enum class PhaseEndReason {
  reached_end,    // the phase's end event (rail entry, lock, rail exit, height)
  cannot_start,   // at rest at the start and the drive cannot move the mast
  stopped,        // the driven frame's speed fell to zero (stall)
  crept_to_rest,  // motor mode: the speed fell below the creep threshold (stall)
  wall_time,      // the run's wall-time cap
  step_limit,     // the run's step budget
  horizon,        // the phase's simulated-time horizon passed with the mast still creeping on
  failure,        // the integrator failed
  model_stop,     // one of the model's stop events (PhaseModel::num_stop_events); see stop_event
};

struct PhaseOutcome {
  PhaseEndReason reason = PhaseEndReason::reached_end;
  double t_end_s = 0;
  PhasePoint end;          // the point at the end (on the event surface when reached)
  double drive_work_J = 0; // integral of F dy_m over the phase
  long steps = 0, rejected_steps = 0, evals = 0;
  std::string message;     // the integrator's message on failure
  int stop_event = -1;     // model_stop: which of the model's stop events fired
  std::vector<double> end_state;  // (q, q') of the model at the end, dof values each
};

// Where a phase's samples go, shared by the stage loop and the solvers.
struct PhaseSinks {
  PeakTracker& peaks;
  PhasePeaks& phase_peaks;  // reset by the solver at the phase start
  HistoryRecorder& history;
  std::chrono::steady_clock::time_point deadline;
  // Whether a closed-form phase reads the clock at its start: a clock read is a sizeable share of
  // a closed-form phase (docs/benchmarks.md), so the stage loop asks every kClockEvery-th segment
  // (a cap overshoots by at most that many phases).
  bool check_clock = true;
  static constexpr int kClockEvery = 8;
  // Time stepping reads the clock once per kClockWork state values stepped over the run (a step
  // of a system of size N counts N; the count goes on across phases, which may be a step or two
  // each): every step of a system of 256 values or more, every 85th of one bay's 3.
  long* clock_work = nullptr;  // the run's count; nullptr: the phase's own
  static constexpr long kClockWork = 256;
};

// Start of a phase: time and the state (q, q') of its model.
struct PhaseStart {
  double t_s = 0;
  const double* q = nullptr;
  const double* qdot = nullptr;
  // Time stepping: below this driven-frame speed (m/s) the mast has crept to rest (a stall);
  // 0 = no creep test.
  double creep_speed_m_per_s = 0;
};

class PhaseSolver {
 public:
  virtual ~PhaseSolver() = default;
  virtual PhaseOutcome solve(const PhaseStart& start, PhaseSinks& sinks) = 0;
};

}  // namespace truss::stages
