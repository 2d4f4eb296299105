// The one stage loop of a run (docs/model.md §2): for each stage of the plan (stage_plan.hpp), its
// start event (impulsive start or unlock), its phases in the segments the plan's stack mode gives
// (stack_model.hpp: held or free), each through its phase solver (phase_solver.hpp: closed form
// or time stepping), and the event that ends each phase (rail entry, latch, rail exit, landing).
// The stack mode computes the events; the loop books them the same way for every mode. Peaks go
// to the PeakTracker, energies to the EnergyLedger, samples to the history; the result is a
// RunResult with one status.
#pragma once
#include <memory>
#include <vector>

#include "model/params.hpp"
#include "stages/result.hpp"
#include "stages/run_options.hpp"
#include "stages/stack_model.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

// Runs the planned stages with the plan's stack mode (`stack`: the caller picks it, so that the loop
// knows no mode by name). The options are not checked again here: they come validated from the
// entry point that built them (sim::simulate, from SceneOptions::validate()).
RunResult run_stages(const model::MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts,
                     std::unique_ptr<StackModel> stack);

}  // namespace truss::stages
