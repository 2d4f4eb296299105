// Dormand-Prince 5(4) embedded Runge-Kutta pair (Dormand & Prince 1980; coefficients, error
// estimate and 4th-order dense output as in Hairer, Norsett & Wanner, Solving ODEs I, DOPRI5),
// FSAL, step control on the RMS of the error scaled by atol + rtol |y|. Events are located on
// the dense output by the Illinois method to IntegratorOptions::event_time_tol.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "integrators/ode.hpp"

namespace truss::integrators {

// Hairer's stiffness test of DOPRI5 (Hairer & Wanner, Solving ODEs II, IV.2): the ratio
// |k7 - k6| / |y7 - y6| of the last two stages estimates |lambda| along the step; h |lambda| beyond
// 3.25 (the stability boundary of DP5 on the negative real axis is about 3.3) on 15 accepted steps
// means the step size is set by stability, not accuracy.
// DOP853 applies the same test with its own boundary, 6.1 (dop853.f), on its last two stages.
struct StiffnessTest {
  double boundary = 3.25;  // h |lambda| beyond which a step counts as stiff
  int stiff_steps = 0, non_stiff = 0;
  // True once the test has fired.
  bool update(double h, const std::vector<double>& k7, const std::vector<double>& k6, const std::vector<double>& y7,
              const std::vector<double>& y6);
};

class DormandPrince54 : public Integrator {
 public:
  explicit DormandPrince54(const IntegratorOptions& opts) : opts_(opts) {}
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y,
                              StepObserver* observer) override;
  // New options for the next calls; the last step size is kept to start the next phase.
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  double calc_scale(double a, double b) const { return opts_.atol + opts_.rtol * std::max(std::abs(a), std::abs(b)); }
  double calc_initial_step(OdeSystem& sys, double t, const double* y, double span, IntegratorSummary& sum);
  double attempt_step(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum);
  void fill_dense(int n, double h, const double* y);
  int find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev);
  IntegratorOptions opts_;
  std::vector<double> k_[7], ytmp_, ynew_, err_, rc_[5], g0_, g1_, gt_, yev_;
  double h_last_ = 0.0;  // last accepted step, reused to start the next call
};

}  // namespace truss::integrators
