#include "sim/simulate.hpp"

#include <chrono>
#include <limits>
#include <memory>
#include <vector>

#include "free_stack/free_stack_model.hpp"
#include "stages/held_stack.hpp"
#include "stages/stage_loop.hpp"
#include "stages/stage_plan.hpp"

namespace truss::sim {
namespace {

// The stack mode of a plan: the one place that knows them all.
std::unique_ptr<stages::StackModel> make_stack_model(const model::MastParams& mast,
                                                     const std::vector<stages::StageSpec>& plan,
                                                     const stages::RunnerOptions& opts) {
  if (!plan.empty() && plan.front().free_stack)
    return std::make_unique<stages::FreeStackModel>(mast, opts, plan.front().contacts);
  return std::make_unique<stages::HeldStack>(mast, opts);
}

}  // namespace

RunResult simulate(const SceneOptions& scene, const model::MastParams& mast) {
  const auto t0 = std::chrono::steady_clock::now();
  auto invalid = [&](std::string msg) {
    RunResult r;
    r.status = RunStatus::invalid_input;
    r.message = std::move(msg);
    r.n_bays = scene.mast.n_bays;
    r.direction = to_string(scene.run.direction);
    r.drive_mode = to_string(scene.drive.mode);
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };
  // Each check once, in the order validate_mast gives them; the stage plan is built once, and
  // run_stages trusts the options from here on.
  std::string e = scene.validate();
  if (e.empty()) e = validate_mast_params(mast);
  std::vector<stages::StageSpec> plan;
  if (e.empty()) e = plan_stages(scene, mast, model::calc_direction_sign(scene.run.direction), plan);
  if (e.empty()) e = validate_panels(mast);
  if (!e.empty()) return invalid(e);

  stages::RunnerOptions ro{scene.drive, scene.run, scene.motorisation};
  ro.wall_start = t0;
  RunResult r = stages::run_stages(mast, plan, ro, make_stack_model(mast, plan, ro));
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

RunResult simulate(const SceneOptions& scene) { return simulate(scene, build_mast(scene)); }

}  // namespace truss::sim
