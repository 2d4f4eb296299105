#include "sim/simulate.hpp"

#include <chrono>
#include <limits>

#include "stages/runner.hpp"
#include "stages/stage_plan.hpp"

namespace truss::sim {

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
  std::string e = scene.validate();
  if (e.empty()) e = validate_mast(mast, scene);
  if (!e.empty()) return invalid(e);

  const double direction = scene.run.direction == Direction::deploy ? 1.0 : -1.0;
  std::vector<stages::StageSpec> plan;
  e = stages::plan_held_stages(mast, direction, plan);
  if (!e.empty()) return invalid(e);

  stages::RunnerOptions ro;
  ro.drive.law = scene.drive.mode == DriveMode::velocity ? stages::DriveLaw::velocity
               : scene.drive.mode == DriveMode::torque   ? stages::DriveLaw::torque
                                                          : stages::DriveLaw::motor;
  ro.drive.direction = direction;
  ro.drive.speed_m_per_s = scene.drive.speed_m_per_s;
  ro.drive.screw_lead_m = scene.drive.screw_lead_m;
  ro.drive.torque_Nm = scene.drive.torque_Nm;
  ro.drive.stall_torque_Nm = scene.drive.stall_torque_Nm;
  ro.drive.no_load_speed_rad_per_s = scene.drive.no_load_speed_rad_per_s;
  ro.integrator = scene.run.integrator == IntegratorKind::cvode ? stages::IntegratorChoice::cvode
                                                                : stages::IntegratorChoice::dopri54;
  ro.integration.rtol = scene.run.rtol;
  ro.integration.atol = scene.run.atol;
  ro.output_step_s = scene.run.output_step_s;
  ro.max_steps = scene.run.max_steps;
  ro.max_wall_time_s = scene.run.max_wall_time_s;
  RunResult r = stages::run_held_stages(mast, plan, ro);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

RunResult simulate(const SceneOptions& scene) { return simulate(scene, build_mast(scene)); }

}  // namespace truss::sim
