#include "integrators/cvode_dense_lu.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace truss::integrators {

namespace {

// The solver's content: its pivots and the clock of its integrator (CVODE passes the linear solver
// no user data).
struct DenseLu {
  std::vector<sunindextype> pivots;
  CallbackDeadline* clock = nullptr;
  sunindextype last_flag = SUNLS_SUCCESS;
};

DenseLu& lu_of(SUNLinearSolver S) { return *static_cast<DenseLu*>(S->content); }

int lu_setup(SUNLinearSolver S, SUNMatrix A) {
  DenseLu& lu = lu_of(S);
  if (SUNMatGetID(A) != SUNMATRIX_DENSE) return static_cast<int>(lu.last_flag = SUNLS_ILL_INPUT);
  realtype** a = SUNDenseMatrix_Cols(A);
  const sunindextype m = SUNDenseMatrix_Rows(A), n = SUNDenseMatrix_Columns(A);
  lu.pivots.resize(static_cast<std::size_t>(n));
  sunindextype* p = lu.pivots.data();
  for (sunindextype k = 0; k < n; ++k) {
    if (lu.clock->passed_now()) return static_cast<int>(lu.last_flag = SUNLS_PACKAGE_FAIL_UNREC);  // CV_LSETUP_FAIL
    realtype* col_k = a[k];
    sunindextype l = k;
    for (sunindextype i = k + 1; i < m; ++i)
      if (std::abs(col_k[i]) > std::abs(col_k[l])) l = i;
    p[k] = l;
    if (col_k[l] == 0.0) {
      lu.last_flag = k + 1;
      return SUNLS_LUFACT_FAIL;  // recoverable: CVODE cuts the step
    }
    if (l != k)
      for (sunindextype i = 0; i < n; ++i) std::swap(a[i][l], a[i][k]);
    const realtype mult = 1.0 / col_k[k];
    for (sunindextype i = k + 1; i < m; ++i) col_k[i] *= mult;
    for (sunindextype j = k + 1; j < n; ++j) {
      realtype* col_j = a[j];
      const realtype a_kj = col_j[k];
      if (a_kj != 0.0)
        for (sunindextype i = k + 1; i < m; ++i) col_j[i] -= a_kj * col_k[i];
    }
  }
  return static_cast<int>(lu.last_flag = SUNLS_SUCCESS);
}

int lu_solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, realtype /*tol*/) {
  DenseLu& lu = lu_of(S);
  N_VScale(1.0, b, x);
  SUNDlsMat_denseGETRS(SUNDenseMatrix_Cols(A), SUNDenseMatrix_Rows(A), lu.pivots.data(), N_VGetArrayPointer(x));
  return static_cast<int>(lu.last_flag = SUNLS_SUCCESS);
}

int lu_free(SUNLinearSolver S) {
  if (S == nullptr) return SUNLS_SUCCESS;
  delete static_cast<DenseLu*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

SUNLinearSolver make_cvode_dense_lu(SUNContext ctx, CallbackDeadline* clock) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (S == nullptr) return nullptr;
  S->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  S->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  S->ops->initialize = [](SUNLinearSolver L) { return static_cast<int>(lu_of(L).last_flag = SUNLS_SUCCESS); };
  S->ops->setup = lu_setup;
  S->ops->solve = lu_solve;
  S->ops->lastflag = [](SUNLinearSolver L) { return lu_of(L).last_flag; };
  S->ops->free = lu_free;
  S->content = new DenseLu{{}, clock, SUNLS_SUCCESS};
  return S;
}

}  // namespace truss::integrators
