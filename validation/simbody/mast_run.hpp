// A deployment of the Simbody mast (mast_system.hpp) through the stages of docs/model.md §2:
//
//   start      held stack: frames 0..n-1 and bays 1..n-1 locked (mobilizer locks), bay n free;
//              free stack: frame 0 locked, every other frame and bay free. Velocity mode locks
//              the driven frame's speed at v (a velocity lock: its motion force is the drive
//              force) and the start is the plastic impulse that brings the rest to a consistent
//              motion (the momentum-consistent kick of the free stack).
//   rail entry an event when the deploying bay's rail function f falls through 0: the rail
//              constraint is enabled (held stack: the lower frame and the bay below are
//              released), and the speeds jump by the plastic impact (mast_impact.hpp).
//   latch      an event when its hinge offset x falls through 0: the bay's two strut pins are
//              locked straight, the rail disabled, the drive moves to the frame below, and the
//              struts' radial motion stops in a plastic impact. The run ends at bay 1's latch.
//
// Between events Simbody integrates the constrained equations (its own coordinate projection);
// after every step the drive force, pin force and diagonal tension are sampled for the peaks.
#pragma once
#include <limits>
#include <string>
#include <vector>

#include "scene.hpp"

namespace mastcheck {

struct RunOptions {
  int longerons_per_bay = 1;      // 1: one longeron with 3x mass/inertia; 3: all three
  std::string integrator = "rkm"; // rkm (Runge-Kutta-Merson), rkf (-Feldberg), rk3, cpodes
  double accuracy = -1;           // < 0: the scene's run.rtol
  double max_time_s = 1e4;        // simulated time cap
  std::string history_path;       // non-empty: one CSV row per sample (step ends and events)
};

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Largest value seen and where (earliest on ties).
struct Peak {
  double value = -std::numeric_limits<double>::infinity();
  double time_s = kNaN;
  int bay = 0;
  void offer(double v, double t, int b) {
    if (v > value) { value = v; time_s = t; bay = b; }
  }
};

struct BayRecord {
  double entry_time_s = kNaN, lock_time_s = kNaN;
  double entry_energy_loss_J = kNaN, latch_energy_J = kNaN;
  double entry_impulse_Ns = kNaN;        // rail impulse on one pin
  double entry_drive_impulse_Ns = kNaN;  // velocity mode: the screws' impulse
  Peak drive_force_N, pin_force_N;       // in the bay's stage (from the previous latch to its own)
};

struct RunSummary {
  std::string status = "time limit";     // "ok" when bay 1 latched; "rail miss" (model.md §2)
  double deploy_time_s = kNaN, end_time_s = kNaN;
  Peak drive_force_N, pin_force_N, diagonal_tension_N;
  double start_drive_impulse_Ns = 0;
  std::vector<BayRecord> bays;           // bays[i], i = 1..n
  long steps = 0, realizations = 0;
  double max_constraint_error = 0;       // largest position-constraint error seen at a step end
  double wall_time_s = 0;                // the run: model build, integration and events
  double cpu_time_s = 0;                 // the same span in process CPU time
};

RunSummary run_deployment(const MastScene& scene, const RunOptions& options);

}  // namespace mastcheck
