// Automatic method choice (run.integrator = "auto"): the explicit Dormand-Prince pair while the
// problem is non-stiff, SUNDIALS CVODE BDF/Newton from the moment Hairer's stiffness test fires
// (embedded_rk.hpp, StiffnessTest), or its step size collapses, to the end of the run. Stiffness in this model comes from the
// scene (a strong motor's torque-speed line is a damper with time constant J_eff / c_motor; stiff
// diagonals), not from a passing phase, so the switch is kept for the rest of the run rather than
// tested back. Non-stiff runs never leave dopri54 and give the same numbers as run.integrator =
// "dopri54".
#pragma once
#include "integrators/cvode_integrator.hpp"
#include "integrators/dopri54.hpp"

namespace truss::integrators {

class AutoIntegrator : public Integrator {
 public:
  explicit AutoIntegrator(const IntegratorOptions& opts);
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) override;
  void set_options(const IntegratorOptions& opts) override;
  // Time at which the run switched to CVODE BDF; NaN while it has not.
  double get_switch_time_s() const { return switch_time_s_; }

 private:
  IntegratorOptions opts_;
  DormandPrince54 explicit_;
  CvodeIntegrator implicit_;
  double switch_time_s_;
};

}  // namespace truss::integrators
