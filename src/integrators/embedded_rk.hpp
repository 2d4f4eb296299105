// One driver for the explicit embedded Runge-Kutta pairs (dopri54.hpp, dop853.hpp): initial step
// (Hairer's heuristic, or the last accepted step of the previous call), step-size control on the
// pair's scaled error with rejection, FSAL, events located on the dense output by the Illinois
// method to IntegratorOptions::event_time_tol, Hairer's stiffness test, the step cap and the
// counters. A pair (RkPair) gives its stages and error estimate, its dense output and the
// constants of its step control (Hairer, Norsett & Wanner, Solving ODEs I, II.4 and II.6).
#pragma once
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "integrators/ode.hpp"

namespace truss::integrators {

// Hairer's stiffness test (Hairer & Wanner, Solving ODEs II, IV.2; DOPRI5 and DOP853): the ratio
// |k_b - k_a| / |y_b - y_a| of two stages at the same time estimates |lambda| along the step;
// h |lambda| beyond the boundary (about the pair's stability boundary on the negative real axis:
// 3.25 for DP5, 6.1 for DOP853) on 15 accepted steps means the step size is set by stability,
// not accuracy; 6 non-stiff steps reset the count.
struct StiffnessTest {
  double boundary = 3.25;  // h |lambda| beyond which a step counts as stiff
  int stiff_steps = 0, non_stiff = 0;
  // True once the test has fired.
  bool update(double h, const std::vector<double>& kb, const std::vector<double>& ka, const std::vector<double>& yb,
              const std::vector<double>& ya);
};

// The weights of the error norm: atol + rtol max(|y|, |y1|) per component.
struct ErrorScale {
  double atol = 0, rtol = 0;
  double operator()(double a, double b) const { return atol + rtol * std::max(std::abs(a), std::abs(b)); }
};

// A step's stages, kept by the driver for its pair: k[0] = f(t, y) on entry (FSAL), the pair's
// other stages, k[fsal] = f(t + h, y1) after the step; ytmp the state of the step's last stage
// (at t + h), y1 the step's end.
struct RkStages {
  std::vector<std::vector<double>> k;
  std::vector<double> ytmp, y1;
};

// What the driver needs to know of a pair.
struct RkPairTraits {
  int order = 5;               // q: initial-step heuristic h ~ (0.01 / |f'|)^(1/q), step ratio 0.9 err^(-1/q)
  int num_stages = 7;          // vectors k, those of the dense output included
  int fsal = 6;                // index of f(t + h, y1), the next step's k[0]
  int last_stage = 5;          // index of the stage at t + h taken at ytmp (the stiffness test's pair with fsal)
  int rhs_per_step = 6;        // right-hand sides of an attempted step (k[0] excluded)
  double stiff_boundary = 3.25;
  double pi_beta = 0.0;        // PI step control (Gustafsson): ratio 0.9 err^(-1/q + 0.75 beta) err_prev^beta
  double ratio_min = 0.2, ratio_max = 10.0;  // bounds of h_new / h
};

class RkPair {
 public:
  virtual ~RkPair() = default;
  virtual const RkPairTraits& traits() const = 0;
  // Sizes the pair's own vectors (dense output) for n unknowns.
  virtual void resize(int n) = 0;
  // One step of size h from (t, y): the stages into s.k[1..], s.ytmp, s.y1 and s.k[fsal]. Returns
  // the scaled error estimate (accepted if <= 1), NaN if the end state is not finite.
  virtual double attempt_step(OdeSystem& sys, double t, double h, const double* y, RkStages& s,
                              const ErrorScale& scale) = 0;
  // The dense output of the accepted step [t, t + h] from y and its stages; returns the
  // right-hand sides it evaluated.
  virtual long fill_dense(OdeSystem& sys, double t, double h, const double* y, RkStages& s) = 0;
  // The filled dense output at t + theta h, theta in [0, 1].
  virtual void calc_dense(double theta, double* y) const = 0;
};

class EmbeddedRungeKutta : public Integrator {
 public:
  EmbeddedRungeKutta(const IntegratorOptions& opts, std::unique_ptr<RkPair> pair);
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) override;
  // New options for the next calls; the last step size is kept to start the next call.
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  class Dense;
  void resize(int n, int num_events);
  double calc_initial_step(OdeSystem& sys, double t, const double* y, double span, IntegratorSummary& sum);
  int find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev);
  IntegratorOptions opts_;
  std::unique_ptr<RkPair> pair_;
  RkStages st_;
  std::vector<double> g0_, g1_, gt_, yev_;
  double h_last_ = 0.0;  // last accepted step, reused to start the next call
};

}  // namespace truss::integrators
