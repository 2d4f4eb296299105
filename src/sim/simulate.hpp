// One deployment or retraction of one mast: options in, RunResult out.
#pragma once
#include "model/params.hpp"
#include "sim/result.hpp"
#include "sim/scene.hpp"

namespace truss::sim {

// Runs the scene with the given (possibly dispersed) mast. Never throws for physical failures:
// a stall, a step limit, etc. come back as RunResult::status with a message.
// The entry point of a run, and the one place its inputs are validated (as Ceres' Solve checks
// Options::IsValid): SceneOptions::validate(), the mast's parameters, its stage plan (the
// geometry) and the panels; invalid input comes back as RunStatus::invalid_input. Nothing below
// it (run_stages, the stage loop) checks them again. The TOML parser runs the same checks when
// it builds a scene from a file, ahead of any run, so that an error names the file and line.
RunResult simulate(const SceneOptions& scene, const model::MastParams& mast);

// Convenience: build_mast(scene) then simulate.
RunResult simulate(const SceneOptions& scene);

}  // namespace truss::sim
