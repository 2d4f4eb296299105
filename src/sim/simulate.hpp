// One deployment or retraction of one mast: options in, RunResult out.
#pragma once
#include "model/params.hpp"
#include "sim/result.hpp"
#include "sim/scene.hpp"

namespace truss::sim {

// Runs the scene with the given (possibly dispersed) mast. Never throws for physical failures:
// a stall, a step limit, etc. come back as RunResult::status with a message. Invalid input
// (scene.validate() or validate_mast() not empty) comes back as RunStatus::invalid_input.
RunResult simulate(const SceneOptions& scene, const model::MastParams& mast);

// Convenience: build_mast(scene) then simulate.
RunResult simulate(const SceneOptions& scene);

}  // namespace truss::sim
