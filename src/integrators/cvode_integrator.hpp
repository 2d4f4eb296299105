// SUNDIALS CVODE (Adams-Moulton, nonstiff, functional iteration) behind the same interface as
// the own RK pair; CVODE's root finding locates the events, CVodeGetDky gives the dense output.
#pragma once
#include "integrators/ode.hpp"

namespace truss::integrators {

class CvodeIntegrator : public Integrator {
 public:
  explicit CvodeIntegrator(const IntegratorOptions& opts) : opts_(opts) {}
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y,
                              StepObserver* observer) override;
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  IntegratorOptions opts_;
};

}  // namespace truss::integrators
