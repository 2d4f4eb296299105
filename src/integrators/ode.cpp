#include "integrators/ode.hpp"

#include <fmt/format.h>

namespace truss::integrators {

const char* to_string(IntegratorStatus s) {
  switch (s) {
    case IntegratorStatus::reached_end: return "reached end";
    case IntegratorStatus::event: return "event";
    case IntegratorStatus::step_limit: return "step limit";
    case IntegratorStatus::stopped_by_observer: return "stopped by observer";
    case IntegratorStatus::failure: return "failure";
    case IntegratorStatus::stiff: return "stiff";
    case IntegratorStatus::deadline: return "wall-clock deadline";
  }
  return "?";
}

std::string IntegratorSummary::to_string() const {
  return fmt::format("{} at t = {:.9g} s: {} steps ({} rejected), {} rhs evaluations{}{}",
                     integrators::to_string(status), t, steps, rejected_steps, rhs_evals,
                     message.empty() ? "" : "; ", message);
}

std::string IntegratorOptions::validate() const {
  if (!(rtol > 0.0 && rtol < 1.0)) return fmt::format("rtol: must lie in (0, 1), got {}", rtol);
  if (!(atol > 0.0)) return fmt::format("atol: must be positive, got {}", atol);
  if (!(initial_step >= 0.0)) return "initial_step: must not be negative";
  if (!(max_step > 0.0)) return "max_step: must be positive";
  if (!(fixed_step >= 0.0)) return "fixed_step: must not be negative";
  if (max_steps <= 0) return "max_steps: must be positive";
  if (!(event_time_tol > 0.0)) return "event_time_tol: must be positive";
  return {};
}

}  // namespace truss::integrators
