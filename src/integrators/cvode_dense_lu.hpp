// CVODE BDF's dense direct linear solver of the Newton systems, as a SUNLinearSolver: SUNDIALS'
// dense LU (the operations of SUNDlsMat_denseGETRF in its order: partial pivoting by rows, then
// the column-wise update, so the factors are those of SUNLinSol_Dense to the bit) and its solve
// (SUNDlsMat_denseGETRS), with the wall-time cap read after every column of the LU: it costs 2n^3/3
// operations, tens of seconds for n = 4,000, and SUNDIALS' own cannot be stopped from outside. A
// factorisation stopped there returns SUNLS_PACKAGE_FAIL_UNREC (CVODE: CV_LSETUP_FAIL); a zero
// pivot SUNLS_LUFACT_FAIL (recoverable: CVODE cuts the step).
#pragma once
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include "integrators/callback_deadline.hpp"

namespace truss::integrators {

// The solver, reading `clock` (kept by its integrator, alive as long as the solver); null if
// SUNDIALS cannot allocate it. Freed by SUNLinSolFree.
SUNLinearSolver make_cvode_dense_lu(SUNContext ctx, CallbackDeadline* clock);

}  // namespace truss::integrators
