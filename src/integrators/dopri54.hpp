// Dormand-Prince 5(4) embedded Runge-Kutta pair (Dormand & Prince 1980; coefficients, error
// estimate and 4th-order dense output as in Hairer, Norsett & Wanner, Solving ODEs I, DOPRI5):
// FSAL, error in the RMS norm scaled by atol + rtol |y|, PI step control (beta = 0.04, step ratio
// in [0.2, 10]), stiffness boundary h |lambda| = 3.25. Driven by EmbeddedRungeKutta.
#pragma once
#include <memory>
#include <vector>

#include "integrators/embedded_rk.hpp"

namespace truss::integrators {

class Dopri54Pair final : public RkPair {
 public:
  const RkPairTraits& traits() const override;
  void resize(int n) override;
  double attempt_step(OdeSystem& sys, double t, double h, const double* y, RkStages& s,
                      const ErrorScale& scale) override;
  long fill_dense(OdeSystem& sys, double t, double h, const double* y, RkStages& s) override;
  void calc_dense(double theta, double* y) const override;

 private:
  std::vector<double> rc_[5];  // dense output coefficients
};

class DormandPrince54 final : public EmbeddedRungeKutta {
 public:
  explicit DormandPrince54(const IntegratorOptions& opts) : EmbeddedRungeKutta(opts, std::make_unique<Dopri54Pair>()) {}
};

}  // namespace truss::integrators
