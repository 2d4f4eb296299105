// SUNDIALS CVODE behind the same interface as the own RK pair, in one of two set-ups:
//   bdf    BDF orders 1-5, Newton iteration, dense direct linear solver with CVODE's difference-
//          quotient Jacobian (n <= 2 dof + 1 is tiny): stiff-capable (slow strong motors, stiff
//          diagonals: the motor line is a stiff damper);
//   adams  Adams-Moulton orders 1-12, fixed-point iteration: non-stiff, no Jacobian.
// CVODE's root finding locates the events, CVodeGetDky gives the dense output.
// One object serves a whole run: the SUNDIALS context, CVODE memory, vectors and nonlinear solver
// are created on the first integrate() and reused by the following calls through CVodeReInit
// (which restarts CVODE at order 1 with a fresh initial step, as a new object would); they are
// recreated only when the system size changes or after CVODE failed. Every SUNDIALS return flag
// is checked: a failure ends the call with IntegratorStatus::failure and names the function and
// the flag.
#pragma once
#include <memory>

#include "integrators/ode.hpp"

namespace truss::integrators {

enum class CvodeMethod { bdf, adams };

class CvodeIntegrator : public Integrator {
 public:
  explicit CvodeIntegrator(const IntegratorOptions& opts, CvodeMethod method = CvodeMethod::bdf);
  ~CvodeIntegrator() override;
  CvodeIntegrator(const CvodeIntegrator&) = delete;             // owns SUNDIALS memory
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;
  // Steps, rejected steps and right-hand side evaluations of the summary count this call only.
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y,
                              StepObserver* observer) override;
  // Applied (tolerances, step bounds, step budget) at the start of the next integrate().
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  struct Solver;  // the SUNDIALS objects (cvode_integrator.cpp)
  IntegratorOptions opts_;
  CvodeMethod method_;
  std::unique_ptr<Solver> solver_;  // created on first use
};

}  // namespace truss::integrators
