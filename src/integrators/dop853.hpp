// DOP853: Hairer's explicit Runge-Kutta pair of order 8 with error estimators of orders 5 and 3
// (coefficients and equations in dop853_tableau.hpp), FSAL, step control on that error in the RMS
// norm scaled by atol + rtol |y| (exponent 1/8, step ratio in [1/3, 6], as dop853.f). Its order
// suits tight tolerances, where its error falls fastest with the step size (docs/benchmarks.md,
// free stack: work-precision). Dense output of order 7 from three more stages, computed only
// when a time inside the step is asked for (an event or touch located, a history sample), so that
// steps that only end cost 12 right-hand sides. Events are located on the dense output by the
// Illinois method to IntegratorOptions::event_time_tol, as DormandPrince54 does.
#pragma once
#include <vector>

#include "integrators/dopri54.hpp"
#include "integrators/ode.hpp"

namespace truss::integrators {

class Dop853 : public Integrator {
 public:
  explicit Dop853(const IntegratorOptions& opts) : opts_(opts) {}
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) override;
  // New options for the next calls; the last step size is kept to start the next phase.
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  class Dense;
  double calc_scale(double a, double b) const { return opts_.atol + opts_.rtol * std::max(std::abs(a), std::abs(b)); }
  double calc_initial_step(OdeSystem& sys, double t, const double* y, double span, IntegratorSummary& sum);
  double attempt_step(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum);
  // The dense output's coefficients r0..r6 of the accepted step [t, t + h] from y (three more stages).
  void fill_dense(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum);
  int find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev);
  IntegratorOptions opts_;
  std::vector<double> k_[16], ytmp_, ynew_, rc_[7], g0_, g1_, gt_;
  std::vector<double> ystart_, ydense_, yroot_;  // dense output: the step's start, its stages' states, event probes
  double h_last_ = 0.0;  // last accepted step, reused to start the next call
};

}  // namespace truss::integrators
