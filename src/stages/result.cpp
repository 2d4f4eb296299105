#include "stages/result.hpp"

#include <cmath>

#include <fmt/format.h>

namespace truss::stages {

const char* to_string(RunStatus s) {
  switch (s) {
    case RunStatus::ok: return "ok";
    case RunStatus::rail_miss: return "rail miss";
    case RunStatus::stall: return "stall";
    case RunStatus::singular_configuration: return "singular configuration";
    case RunStatus::step_limit: return "step limit";
    case RunStatus::invalid_input: return "invalid input";
    case RunStatus::wall_time_limit: return "wall-time limit";
    case RunStatus::solver_failure: return "solver failure";
    case RunStatus::inaccurate: return "inaccurate";
  }
  return "?";
}

std::string RunResult::to_string() const {
  std::string s = fmt::format("status: {}{}{}\n", stages::to_string(status), message.empty() ? "" : " - ", message);
  s += fmt::format("{} of {} bays, {} drive: {} bays completed\n", direction, n_bays, drive_mode, bays_completed);
  if (std::isfinite(deploy_time_s)) s += fmt::format("  {} time            {:.9g} s\n", direction, deploy_time_s);
  else s += fmt::format("  {} time            not reached (status {})\n", direction, stages::to_string(status));
  s += fmt::format("  run ended at           {:.9g} s\n", end_time_s);
  s += fmt::format("  peak drive force       {:.6g} N at t = {:.6g} s (bay {})\n", peak_drive_force_N, peak_drive_force_time_s, peak_drive_force_bay);
  s += fmt::format("  min drive force        {:.6g} N at t = {:.6g} s (bay {})\n", min_drive_force_N, min_drive_force_time_s, min_drive_force_bay);
  s += fmt::format("  peak drive torque      {:.6g} N m\n", peak_drive_torque_Nm);
  s += fmt::format("  peak rail pin force    {:.6g} N at t = {:.6g} s (bay {})\n", peak_pin_force_N, peak_pin_force_time_s, peak_pin_force_bay);
  s += fmt::format("  peak diagonal tension  {:.6g} N\n", peak_diagonal_tension_N);
  s += fmt::format("  drive work             {:.9g} J (smooth {:.9g} J, impulses {:.9g} J)\n", drive_work_J, drive_work_smooth_J, drive_work_impulses_J);
  s += fmt::format("  energy lost in impacts {:.9g} J\n", energy_lost_J);
  s += fmt::format("  energy residual        {:.3g} J\n", energy_residual_J);
  s += fmt::format("  steps {} (rejected {}), model evaluations {}, wall time {:.3g} s\n", steps, rejected_steps, rhs_evals, wall_time_s);
  return s;
}

}  // namespace truss::stages
