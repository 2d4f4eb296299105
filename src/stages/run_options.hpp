// Options of one run: the scene's [run] table (sim::RunOptions is this struct) and what the stage
// loop needs besides. Plain structs with a default and a reason per field. RunOptions::validate()
// names the first bad field; it is part of SceneOptions::validate(), which the run's entry point
// (sim::simulate) calls once: the stage loop does not check its options again.
#pragma once
#include <chrono>
#include <string>

#include "integrators/ode.hpp"
#include "model/drive.hpp"
#include "model/motorisation.hpp"

namespace truss::stages {

// The one statement of the sane tolerance ranges (RunOptions::validate and the scene key table's
// hard ranges both read these). Below 1e-14 (about 50 ulp) no step can meet rtol in double
// precision; above 1e-2 the solution is not worth reporting. atol is in m, m/s and J: beyond 1 mm
// the error control no longer sees the motion of a bay (l_s = 0.18 m in Table 1); it must be > 0.
inline constexpr double kMinRtol = 1e-14, kMaxRtol = 1e-2, kMaxAtol = 1e-3;

struct RunOptions {
  model::Direction direction = model::Direction::deploy;  // deploy from the stowed stack, or retract into it
  double output_step_s = 0.0;               // time-history sample step; 0 = no histories (fastest)
  double rtol = 1e-8;                       // relative tolerance of the ODE integrators
  double atol = 1e-10;                      // absolute tolerance (m, m/s, J) of the ODE integrators
  integrators::IntegratorKind integrator = integrators::IntegratorKind::automatic;  // dopri54, BDF once stiff (ode.hpp)
  long max_steps = 2'000'000;               // step cap over the whole run: a run never hangs
  double max_wall_time_s = 600.0;           // wall-time cap for one run
  long max_history_bytes = 16'000'000;      // history memory cap (B, stages/history.hpp): beyond it the step doubles
  std::string validate() const;             // empty, or "run.key: reason"
};

struct RunnerOptions {
  model::DriveParams drive;                  // the scene's [drive] table
  RunOptions run;                            // the scene's [run] table
  model::MotorisationFactors motorisation;   // the scene's [motorisation] table
  int peak_samples_per_piece = 4;            // velocity mode: samples a smooth piece, with their loads' rates (>= 3)
  // When the run started (its wall-time cap counts from here, the stage plan and the stack
  // model's set-up included); the epoch: when run_stages starts.
  std::chrono::steady_clock::time_point wall_start{};
  // Integrator options of the run (tolerances; the step budget is set per phase).
  integrators::IntegratorOptions calc_integrator_options() const;
};

}  // namespace truss::stages
