#include "integrators/auto_integrator.hpp"

#include <algorithm>
#include <limits>

namespace truss::integrators {

namespace {
IntegratorOptions with_stiffness_test(IntegratorOptions o) {
  o.stop_when_stiff = true;
  return o;
}
}  // namespace

AutoIntegrator::AutoIntegrator(const IntegratorOptions& opts)
    : opts_(opts), explicit_(with_stiffness_test(opts)), implicit_(opts, CvodeMethod::bdf),
      switch_time_s_(std::numeric_limits<double>::quiet_NaN()) {}

void AutoIntegrator::set_options(const IntegratorOptions& opts) {
  opts_ = opts;
  explicit_.set_options(with_stiffness_test(opts));
  implicit_.set_options(opts);
}

IntegratorSummary AutoIntegrator::integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) {
  if (switch_time_s_ == switch_time_s_) return implicit_.integrate(sys, t0, t_end, y, observer);
  const IntegratorSummary first = explicit_.integrate(sys, t0, t_end, y, observer);
  // A step size that collapses (underflow) is the other face of stiffness for an explicit pair:
  // the state at first.t is the last accepted one, so BDF takes over from there as well.
  if (first.status != IntegratorStatus::stiff && first.status != IntegratorStatus::failure) return first;
  switch_time_s_ = first.t;
  // The rest of the call's step budget goes to CVODE, which continues from the accepted state.
  IntegratorOptions rest = opts_;
  rest.max_steps = std::max(1L, opts_.max_steps - first.steps);
  implicit_.set_options(rest);
  IntegratorSummary second = implicit_.integrate(sys, first.t, t_end, y, observer);
  implicit_.set_options(opts_);
  second.steps += first.steps;
  second.rejected_steps += first.rejected_steps;
  second.rhs_evals += first.rhs_evals;
  return second;
}

}  // namespace truss::integrators
