#include "stages/run_options.hpp"

#include <cmath>

#include <fmt/format.h>

namespace truss::stages {

namespace {
std::string positive(const char* key, double v) {
  if (!(std::isfinite(v) && v > 0.0)) return fmt::format("{}: must be a positive number, got {}", key, v);
  return {};
}
}  // namespace

std::string RunOptions::validate() const {
  if (!(std::isfinite(output_step_s) && output_step_s >= 0.0))
    return fmt::format("run.output_step_s: must be >= 0 (0 = no time histories), got {}", output_step_s);
  if (!(rtol >= kMinRtol && rtol <= kMaxRtol))
    return fmt::format("run.rtol: must lie in [{}, {}] (relative error per step), got {}", kMinRtol, kMaxRtol, rtol);
  if (!(atol > 0.0 && atol <= kMaxAtol))
    return fmt::format("run.atol: must lie in (0, {}] (m, m/s, J per step), got {}", kMaxAtol, atol);
  if (!(max_history_bytes >= 1000))
    return fmt::format("run.max_history_bytes: must be >= 1000, got {}", max_history_bytes);
  if (max_steps < 1) return fmt::format("run.max_steps: must be positive, got {}", max_steps);
  return positive("run.max_wall_time_s", max_wall_time_s);
}

integrators::IntegratorOptions RunnerOptions::calc_integrator_options() const {
  integrators::IntegratorOptions io;
  io.rtol = run.rtol;
  io.atol = run.atol;
  return io;
}

}  // namespace truss::stages
