// SUNDIALS IDA behind the same interface as the own RK pairs and CVODE: it integrates the
// residual form of a system (OdeSystem::dae_form(): F(t, y, y', z) = 0, z algebraic), not
// y' = f(t, y). Variable-order BDF (orders 1-5) with Newton iteration on a banded difference-quotient
// Jacobian (IDA's own increments, each kept within a fraction of its unknown's smooth length,
// DaeForm::calc_smooth_lengths) and a banded direct linear solver (SUNBandMatrix, SUNLinSol_Band).
// IDA's vectors hold the unknowns in the order the form gives (DaeForm::find_band_order; the free
// stack's phases, each frame's q and q' side by side), in which the Jacobian is banded: per
// Jacobian, lower + upper + 1 residual evaluations (each O(n)) and an O(N lower (lower + upper))
// LU, so every step is O(n) for an n-frame phase. A form without an order keeps its own with a full band (a dense Jacobian).
// The algebraic unknowns are excluded from the local error test (IDASetSuppressAlg): they are
// fixed by the constraints at each step; the error weights are IDA's own scaled by the form's error
// factors (DaeForm::calc_error_factors: a frame height near a straight bay is held to the bay's
// hinge offset); consistent initial values of z and of y' for the given y
// come from IDACalcIC (IDA_YA_YDP_INIT) at every start. IDA's root finding locates the events on
// y (the first size() entries), IDAGetDky gives the dense output of y; the step loop is
// SundialsIntegrator's (sundials_integrator.hpp). One object serves a run: context and memory are
// created on first use and restarted with IDAReInit; recreated when the size changes or after IDA
// failed.
#pragma once
#include <memory>

#include "integrators/sundials_integrator.hpp"

namespace truss::integrators {

// IDA as the solver of a SundialsIntegrator; it integrates systems that have a DaeForm.
std::unique_ptr<SundialsSolver> make_ida_solver();

class IdaIntegrator final : public SundialsIntegrator {
 public:
  explicit IdaIntegrator(const IntegratorOptions& opts) : SundialsIntegrator(opts, make_ida_solver()) {}
};

}  // namespace truss::integrators
