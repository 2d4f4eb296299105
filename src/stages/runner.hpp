// One runner executes the stages of a run (stage_plan.hpp) with either
//  - closed-form kinematics and inverse dynamics (velocity drive, held stack: every stage is
//    kinematic, no time stepping), or
//  - an ODE integrator (torque and motor drives) on each phase, with the phase's end, a stall,
//    and the impacts between phases located as events.
// It tracks peaks (bracketed, then refined by a scalar maximisation), drive work, impacts, the
// energy balance and optional time histories, and fills a sim::RunResult.
#pragma once
#include <vector>

#include "integrators/ode.hpp"
#include "model/params.hpp"
#include "sim/result.hpp"
#include "stages/held_phase.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

enum class IntegratorChoice { dopri54, cvode };

struct RunnerOptions {
  DriveParams drive;                           // drive law and direction
  IntegratorChoice integrator = IntegratorChoice::dopri54;  // torque / motor modes
  integrators::IntegratorOptions integration;  // tolerances and per-call caps
  double output_step_s = 0.0;                  // time-history step; 0 = none
  long max_steps = 2'000'000;                  // total step cap of the run
  double max_wall_time_s = 600.0;              // wall-time cap of the run
  int peak_samples_per_piece = 9;              // velocity mode: bracketing grid per smooth piece
};

sim::RunResult run_held_stages(const model::MastParams& mast, const std::vector<StageSpec>& stages,
                               const RunnerOptions& opts);

}  // namespace truss::stages
