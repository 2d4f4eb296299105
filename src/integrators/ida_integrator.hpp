// SUNDIALS IDA behind the same interface as the own RK pair and CVODE: it integrates the
// residual form of a system (OdeSystem::dae_form(): F(t, y, y', z) = 0, z algebraic), not
// y' = f(t, y). Variable-order BDF (orders 1-5) with Newton iteration on a dense direct linear
// solver (SUNLinSol_Dense) and IDA's difference-quotient Jacobian: per Jacobian, N + k residual
// evaluations (each O(N)) and an O((N + k)^3) LU, so O(n^2) and O(n^3) work per Jacobian for an
// n-frame phase (N = 2n + 1). That is cheap for the free stack's tens of frames and is meant as a
// cross-check of the direct O(n) bordered solve, not as the production solver of long masts.
// The algebraic unknowns are excluded from the local error test (IDASetSuppressAlg): they are
// fixed by the constraints at each step; consistent initial values of z and of y' for the given y
// come from IDACalcIC (IDA_YA_YDP_INIT) at every start. IDA's root finding locates the events on
// y (the first size() entries), IDAGetDky gives the dense output of y. One object serves a run:
// context and memory are created on first use and restarted with IDAReInit; recreated when the
// size changes or after IDA failed. Every SUNDIALS return flag is checked (as check_retval in the
// SUNDIALS examples, e.g. idaRoberts_dns): a failure ends the call with IntegratorStatus::failure
// naming the function and the flag.
#pragma once
#include <memory>

#include "integrators/ode.hpp"

namespace truss::integrators {

class IdaIntegrator : public Integrator {
 public:
  explicit IdaIntegrator(const IntegratorOptions& opts);
  ~IdaIntegrator() override;
  IdaIntegrator(const IdaIntegrator&) = delete;             // owns SUNDIALS memory
  IdaIntegrator& operator=(const IdaIntegrator&) = delete;
  // sys must have a DaeForm; steps, rejected steps and residual evaluations count this call only.
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y,
                              StepObserver* observer) override;
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  struct Solver;  // the SUNDIALS objects (ida_integrator.cpp)
  IntegratorOptions opts_;
  std::unique_ptr<Solver> solver_;
};

}  // namespace truss::integrators
