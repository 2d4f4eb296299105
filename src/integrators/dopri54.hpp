// Dormand-Prince 5(4) embedded Runge-Kutta pair (Dormand & Prince 1980; coefficients, error
// estimate and 4th-order dense output as in Hairer, Norsett & Wanner, Solving ODEs I, DOPRI5):
// FSAL, error in the RMS norm scaled by atol + rtol |y|, PI step control (beta = 0.04, step ratio
// in [0.2, 10]), stiffness boundary h |lambda| = 3.25. Driven by EmbeddedRungeKutta.
#pragma once
#include <memory>

#include "integrators/embedded_rk.hpp"

namespace truss::integrators {

// The pair, for EmbeddedRungeKutta.
std::unique_ptr<RkPair> make_dopri54_pair();

class DormandPrince54 final : public EmbeddedRungeKutta {
 public:
  explicit DormandPrince54(const IntegratorOptions& opts) : EmbeddedRungeKutta(opts, make_dopri54_pair()) {}
};

}  // namespace truss::integrators
