// DOP853: Hairer's explicit Runge-Kutta pair of order 8 with error estimators of orders 5 and 3
// (coefficients and equations in dop853_tableau.hpp), FSAL, step control on that error in the RMS
// norm scaled by atol + rtol |y| (exponent 1/8, step ratio in [0.333, 6], as dop853.f), stiffness
// boundary h |lambda| = 6.1. Its order suits tight tolerances, where its error falls fastest with
// the step size (docs/benchmarks.md, free stack: work-precision). Dense output of order 7 from
// three more stages, computed only when a time inside the step is asked for (an event or touch
// located, a history sample), so that steps that only end cost 12 right-hand sides. Driven by
// EmbeddedRungeKutta.
#pragma once
#include <memory>

#include "integrators/embedded_rk.hpp"

namespace truss::integrators {

// The pair, for EmbeddedRungeKutta.
std::unique_ptr<RkPair> make_dop853_pair();

class Dop853 final : public EmbeddedRungeKutta {
 public:
  explicit Dop853(const IntegratorOptions& opts) : EmbeddedRungeKutta(opts, make_dop853_pair()) {}
};

}  // namespace truss::integrators
