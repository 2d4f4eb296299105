// SUNDIALS CVODE behind the same interface as the own RK pairs, in one of two set-ups:
//   bdf    BDF orders 1-5, Newton iteration, a dense direct linear solver (cvode_dense_lu.hpp) on
//          a difference-quotient Jacobian of the code's own (n <= 2 dof + 1 is small):
//          stiff-capable (slow strong motors, stiff diagonals: the motor line is a stiff damper);
//   adams  Adams-Moulton orders 1-12, fixed-point iteration: non-stiff, no Jacobian.
// CVODE's root finding locates the events, CVodeGetDky gives the dense output; the step loop is
// SundialsIntegrator's (sundials_integrator.hpp). One object serves a whole run: the context, CVODE
// memory, vectors and solvers are created on the first integrate() and reused by the following
// calls through CVodeReInit (which restarts CVODE at order 1 with a fresh initial step, as a new
// object would); they are recreated only when the system size changes or after CVODE failed.
#pragma once
#include <memory>

#include "integrators/sundials_integrator.hpp"

namespace truss::integrators {

enum class CvodeMethod { bdf, adams };

// CVODE as the solver of a SundialsIntegrator.
std::unique_ptr<SundialsSolver> make_cvode_solver(CvodeMethod method);

class CvodeIntegrator final : public SundialsIntegrator {
 public:
  explicit CvodeIntegrator(const IntegratorOptions& opts, CvodeMethod method = CvodeMethod::bdf)
      : SundialsIntegrator(opts, make_cvode_solver(method)) {}
};

}  // namespace truss::integrators
