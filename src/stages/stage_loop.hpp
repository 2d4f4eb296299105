// The one stage loop of a run (docs/model.md §2): for each stage of the plan (stage_plan.hpp), its
// start event (impulsive start or unlock, model/impacts.hpp), its phases through a phase solver
// (phase_solver.hpp: closed form in velocity mode, time stepping otherwise), and the impact that
// ends each phase (rail entry, latch, rail exit, landing). Peaks go to the PeakTracker, energies
// to the EnergyLedger, samples to the history; the result is a RunResult with one status.
#pragma once
#include <vector>

#include "model/params.hpp"
#include "stages/result.hpp"
#include "stages/run_options.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

// Runs the planned stages. Invalid options come back as RunStatus::invalid_input.
RunResult run_stages(const model::MastParams& mast, const std::vector<StageSpec>& stages, const RunnerOptions& opts);

}  // namespace truss::stages
