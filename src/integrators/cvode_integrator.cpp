#include "integrators/cvode_integrator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <exception>
#include <string>
#include <vector>

#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_dense.h>
#include <sundials/sundials_linearsolver.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrators/callback_deadline.hpp"
#include "integrators/sundials_checks.hpp"
#include "integrators/sundials_common.hpp"
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

namespace truss::integrators {

namespace {

using Clock = std::chrono::steady_clock;

// What CVODE's callbacks need; the system changes with every integrate() call.
struct UserData {
  void* mem = nullptr;       // CVODE's memory (the Jacobian reads the step size and error weights)
  N_Vector ewt = nullptr;    // scratch for the error weights
  OdeSystem* sys = nullptr;
  long rhs_evals = 0;
  long nonfinite_rhs = 0;    // evaluations that returned NaN or inf (CVODE retried smaller steps)
  std::exception_ptr error;  // thrown by the system inside a callback, rethrown after CVode returns
  // The wall-time cap: the right-hand side reads it every few evaluations (so every few columns of
  // a difference-quotient Jacobian) and the LU after every column (lu_setup).
  CallbackDeadline clock;
};

int rhs_fn(realtype t, N_Vector y, N_Vector ydot, void* ud) {
  auto* d = static_cast<UserData*>(ud);
  if (d->clock.passed_every()) return -1;  // unrecoverable: CVode returns, reported as IntegratorStatus::deadline
  try {
    d->sys->calc_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  } catch (...) {
    d->error = std::current_exception();
    return -1;  // unrecoverable: CVode returns CV_RHSFUNC_FAIL, the exception is rethrown
  }
  ++d->rhs_evals;
  for (sunindextype i = 0; i < N_VGetLength(ydot); ++i)
    if (!std::isfinite(N_VGetArrayPointer(ydot)[i])) {
      ++d->nonfinite_rhs;
      return 1;  // recoverable: CVODE cuts the step
    }
  return 0;
}

// The Newton matrix's Jacobian by forward differences, column by column, with CVODE's own
// increments (cvLsDenseDQJac: max(sqrt(eps) |y_j|, 1000 |h| eps N ||f|| / w_j)). Where y + inc e_j
// gives a non-finite right-hand side the column is the backward difference instead: near a
// singular configuration (a bay within a few 1e-9 m of straight, beyond which the mass matrix is
// not positive definite) CVODE's forward increment of a frame height, about 1e-8 m, leaves the
// region where the equations hold, and without this every Jacobian failed at any step size.
int jac_fn(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* ud, N_Vector ftemp, N_Vector, N_Vector) {
  auto* d = static_cast<UserData*>(ud);
  realtype h = 0.0;
  if (CVodeGetCurrentStep(d->mem, &h) < 0 || CVodeGetErrWeights(d->mem, d->ewt) < 0) return -1;
  const sunindextype n = N_VGetLength(y);
  const double eps = std::numeric_limits<double>::epsilon(), srur = std::sqrt(eps);
  const double fnorm = N_VWrmsNorm(fy, d->ewt);
  const double min_inc = fnorm != 0.0 ? 1000.0 * std::abs(h) * eps * static_cast<double>(n) * fnorm : 1.0;
  double* yd = N_VGetArrayPointer(y);
  const double* w = N_VGetArrayPointer(d->ewt);
  const double* f0 = N_VGetArrayPointer(fy);
  const double* f1 = N_VGetArrayPointer(ftemp);
  for (sunindextype j = 0; j < n; ++j) {
    const double yj = yd[j], inc = std::max(srur * std::abs(yj), min_inc / w[j]);
    double* col = SUNDenseMatrix_Column(J, j);
    int flag = 1;
    for (const double step : {inc, -inc}) {
      yd[j] = yj + step;
      flag = rhs_fn(t, y, ftemp, ud);
      if (flag != 0) continue;
      for (sunindextype i = 0; i < n; ++i) col[i] = (f1[i] - f0[i]) / step;
      break;
    }
    yd[j] = yj;
    if (flag != 0) return flag;  // recoverable (1): CVODE cuts the step; an exception or the deadline (-1): fatal
  }
  return 0;
}

// The dense direct linear solver of the Newton systems: SUNDIALS' dense LU (the operations of
// SUNDlsMat_denseGETRF in its order: partial pivoting by rows, then the column-wise update, so the
// factors are those of SUNLinSol_Dense to the bit) and its solve (SUNDlsMat_denseGETRS), with the
// wall-time cap read after every column of the LU: it costs 2n^3/3 operations, tens of seconds for
// n = 4,000, and SUNDIALS' own cannot be stopped from outside. The solver's content owns its
// pivots and points at its integrator's UserData (CVODE passes the linear solver no user data).
struct DenseLu {
  std::vector<sunindextype> pivots;
  UserData* ud = nullptr;
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
    if (lu.ud->clock.passed_now()) return static_cast<int>(lu.last_flag = SUNLS_PACKAGE_FAIL_UNREC);  // CV_LSETUP_FAIL
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

// A DenseLu solver for the integrator whose callbacks use `ud`; null if SUNDIALS cannot allocate.
SUNLinearSolver make_dense_lu(SUNContext ctx, UserData* ud) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (S == nullptr) return nullptr;
  S->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  S->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  S->ops->initialize = [](SUNLinearSolver L) { return static_cast<int>(lu_of(L).last_flag = SUNLS_SUCCESS); };
  S->ops->setup = lu_setup;
  S->ops->solve = lu_solve;
  S->ops->lastflag = [](SUNLinearSolver L) { return lu_of(L).last_flag; };
  S->ops->free = lu_free;
  S->content = new DenseLu{{}, ud, SUNLS_SUCCESS};
  return S;
}

int root_fn(realtype t, N_Vector y, realtype* g, void* ud) {
  auto* d = static_cast<UserData*>(ud);
  return sundials::call_events(*d->sys, d->error, t, N_VGetArrayPointer(y), g);
}

std::string flag_name(int flag) { return sunflags::flag_name(CVodeGetReturnFlagName, flag); }
bool check_flag(int flag, const char* function, IntegratorSummary& sum) {
  return sunflags::check_flag(flag, "CVODE", CVodeGetReturnFlagName, function, sum);
}
bool check_null(const void* p, const char* function, IntegratorSummary& sum) {
  return sunflags::check_null(p, "CVODE", function, sum);
}

// y: CVODE's vector as it is.
void copy_vector(N_Vector v, double* y) { std::copy_n(N_VGetArrayPointer(v), N_VGetLength(v), y); }

}  // namespace

// The SUNDIALS objects of one integrator, kept across integrate() calls.
struct CvodeIntegrator::Solver {
  sundials::Context ctx;  // first: freed last
  void* mem = nullptr;
  N_Vector y = nullptr, tmp = nullptr, ewt = nullptr;
  SUNNonlinearSolver nls = nullptr;  // adams: fixed point (bdf: CVODE's own Newton solver)
  SUNMatrix A = nullptr;             // bdf: dense Newton matrix
  SUNLinearSolver ls = nullptr;      // bdf: dense LU
  CvodeMethod method = CvodeMethod::bdf;
  int n = -1;  // size of y, tmp and the CVODE memory; -1: none
  UserData ud;

  ~Solver() {
    free_problem();
  }
  // Everything but the context (in the order of the SUNDIALS examples).
  void free_problem() {
    if (mem) CVodeFree(&mem);
    if (nls) SUNNonlinSolFree(nls);
    nls = nullptr;
    if (ls) SUNLinSolFree(ls);
    ls = nullptr;
    if (A) SUNMatDestroy(A);
    A = nullptr;
    if (y) N_VDestroy(y);
    if (tmp) N_VDestroy(tmp);
    if (ewt) N_VDestroy(ewt);
    y = tmp = ewt = nullptr;
    n = -1;
  }

  // CVODE memory, vectors and the method's solvers for systems of size n_new.
  bool create(int n_new, double t0, IntegratorSummary& sum) {
    free_problem();
    if (!ctx.ensure("CVODE", sum)) return false;
    y = N_VNew_Serial(n_new, ctx.get());
    if (!check_null(y, "N_VNew_Serial", sum)) return false;
    tmp = N_VNew_Serial(n_new, ctx.get());
    if (!check_null(tmp, "N_VNew_Serial", sum)) return false;
    ewt = N_VNew_Serial(n_new, ctx.get());
    if (!check_null(ewt, "N_VNew_Serial", sum)) return false;
    N_VConst(0.0, y);
    mem = CVodeCreate(method == CvodeMethod::bdf ? CV_BDF : CV_ADAMS, ctx.get());
    if (!check_null(mem, "CVodeCreate", sum)) return false;
    if (!check_flag(CVodeSetErrHandlerFn(mem, sunflags::silent, nullptr), "CVodeSetErrHandlerFn", sum)) return false;
    if (!check_flag(CVodeInit(mem, rhs_fn, t0, y), "CVodeInit", sum)) return false;
    if (!check_flag(CVodeSetUserData(mem, &ud), "CVodeSetUserData", sum)) return false;
    ud.mem = mem;
    ud.ewt = ewt;
    if (method == CvodeMethod::bdf) {
      // Newton (CVODE's default nonlinear solver) on a dense matrix; difference quotients (jac_fn)
      // cost n extra right-hand sides per Jacobian.
      A = SUNDenseMatrix(n_new, n_new, ctx.get());
      if (!check_null(A, "SUNDenseMatrix", sum)) return false;
      ls = make_dense_lu(ctx.get(), &ud);  // SUNLinSol_Dense's LU, stoppable at the wall-time cap
      if (!check_null(ls, "SUNLinSolNewEmpty", sum)) return false;
      if (!check_flag(CVodeSetLinearSolver(mem, ls, A), "CVodeSetLinearSolver", sum)) return false;
      if (!check_flag(CVodeSetJacFn(mem, jac_fn), "CVodeSetJacFn", sum)) return false;
    } else {
      nls = SUNNonlinSol_FixedPoint(y, 0, ctx.get());
      if (!check_null(nls, "SUNNonlinSol_FixedPoint", sum)) return false;
      if (!check_flag(CVodeSetNonlinearSolver(mem, nls), "CVodeSetNonlinearSolver", sum)) return false;
      if (!check_flag(CVodeSetMaxOrd(mem, 12), "CVodeSetMaxOrd", sum)) return false;
    }
    n = n_new;
    return true;
  }

  // Restart CVODE on sys from (t0, y0) with the options and events of this call.
  bool prepare(OdeSystem& sys, double t0, double t_end, const double* y0,
               const IntegratorOptions& o, IntegratorSummary& sum) {
    const int n_sys = sys.size();
    if (n_sys != n && !create(n_sys, t0, sum)) return false;
    ud.sys = &sys;
    ud.rhs_evals = 0;
    ud.nonfinite_rhs = 0;
    ud.error = nullptr;
    double* p = N_VGetArrayPointer(y);
    for (int i = 0; i < n; ++i) p[i] = y0[i];
    // History, order, step counters and initial step choice start afresh.
    if (!check_flag(CVodeReInit(mem, t0, y), "CVodeReInit", sum)) return false;
    if (!check_flag(CVodeSStolerances(mem, o.rtol, o.atol), "CVodeSStolerances", sum)) return false;
    if (!check_flag(CVodeSetMaxNumSteps(mem, o.max_steps), "CVodeSetMaxNumSteps", sum)) return false;
    // After CVodeReInit (CVodeSetStopTime checks tstop against the current step once nst > 0).
    if (!check_flag(CVodeSetStopTime(mem, t_end), "CVodeSetStopTime", sum)) return false;
    // 0 restores CVODE's defaults: no cap, CVODE's own initial step estimate.
    if (!check_flag(CVodeSetMaxStep(mem, std::isfinite(o.max_step) ? o.max_step : 0.0), "CVodeSetMaxStep", sum))
      return false;
    if (!check_flag(CVodeSetInitStep(mem, o.initial_step), "CVodeSetInitStep", sum)) return false;
    // Root functions: dropped and allocated again, so that directions and the inactive-root
    // flags of the last call do not carry over (CVodeRootInit with an unchanged count keeps them).
    if (!check_flag(CVodeRootInit(mem, 0, nullptr), "CVodeRootInit", sum)) return false;
    const int ne = sys.num_events();
    if (ne > 0) {
      if (!check_flag(CVodeRootInit(mem, ne, root_fn), "CVodeRootInit", sum)) return false;
      std::vector<int> dirs(ne);
      for (int e = 0; e < ne; ++e) dirs[e] = sys.event_direction(e);
      if (!check_flag(CVodeSetRootDirection(mem, dirs.data()), "CVodeSetRootDirection", sum)) return false;
      if (!check_flag(CVodeSetNoInactiveRootWarn(mem), "CVodeSetNoInactiveRootWarn", sum)) return false;
    }
    return true;
  }
};

CvodeIntegrator::CvodeIntegrator(const IntegratorOptions& opts, CvodeMethod method) : opts_(opts), method_(method) {}
CvodeIntegrator::~CvodeIntegrator() = default;

IntegratorSummary CvodeIntegrator::integrate(OdeSystem& sys, double t0, double t_end, double* y0,
                                             StepObserver* observer) {
  IntegratorSummary sum;
  sum.t = t0;
  if (const std::string bad = opts_.validate(); !bad.empty()) {
    sum.status = IntegratorStatus::failure;
    sum.message = "invalid integrator options: " + bad;
    return sum;
  }
  if (!(t_end > t0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  if (sys.size() <= 0) {
    sum.status = IntegratorStatus::failure;
    sum.message = fmt::format("CVODE: system size must be positive, got {}", sys.size());
    return sum;
  }
  if (!solver_) {
    solver_ = std::make_unique<Solver>();
    solver_->method = method_;
  }
  Solver& cv = *solver_;
  cv.ud.clock.reset(observer ? observer->deadline() : Clock::time_point::max());
  if (!cv.prepare(sys, t0, t_end, y0, opts_, sum)) {
    cv.free_problem();  // start from new SUNDIALS objects next time
    return sum;
  }
  const int n = cv.n;
  const int ne = sys.num_events();
  auto copy_state = [&] {
    const double* p = N_VGetArrayPointer(cv.y);
    for (int i = 0; i < n; ++i) y0[i] = p[i];
  };
  // A CVODE failure after the start: the state reached is returned, and the objects are
  // recreated on the next call rather than restarted from an unknown state.
  auto failed = [&] {
    cv.free_problem();
    return sum;
  };
  sundials::Dense dense(CVodeGetDky, cv.mem, cv.tmp, n, copy_vector);
  double t = t0;
  std::vector<int> roots(ne);
  while (true) {
    // The step budget of the call. CVodeSetMaxNumSteps alone does not enforce it: CVODE counts
    // steps per CVode() call, and in CV_ONE_STEP mode every call takes one step.
    if (sum.steps >= opts_.max_steps) {
      sum.status = IntegratorStatus::step_limit;
      sum.message = fmt::format("step limit of {} reached", opts_.max_steps);
      return sum;
    }
    double t_prev = t;
    const int flag = CVode(cv.mem, t_end, cv.y, &t, CV_ONE_STEP);
    if (cv.ud.error) {
      const std::exception_ptr e = cv.ud.error;
      cv.free_problem();
      std::rethrow_exception(e);
    }
    long steps = 0, fails = 0;
    if (!check_flag(CVodeGetNumSteps(cv.mem, &steps), "CVodeGetNumSteps", sum)) return failed();
    if (!check_flag(CVodeGetNumErrTestFails(cv.mem, &fails), "CVodeGetNumErrTestFails", sum)) return failed();
    sum.steps = steps;
    sum.rejected_steps = fails;

    sum.rhs_evals = cv.ud.rhs_evals;
    sum.t = t;
    if (flag < 0 && cv.ud.clock.hit) {
      copy_state();
      sum.status = IntegratorStatus::deadline;
      sum.message = fmt::format("wall-clock deadline passed inside a CVODE step at t = {:.9g} s", t);
      return failed();
    }
    if (flag < 0) {
      copy_state();
      sum.status = flag == CV_TOO_MUCH_WORK ? IntegratorStatus::step_limit : IntegratorStatus::failure;
      sum.message = fmt::format("CVODE flag {} ({}) at t = {:.9g} s", flag, flag_name(flag), t);
      return failed();
    }
    // A step that left t unchanged (t + h == t: the step size fell below the resolution of t,
    // typically at the edge of a region where the right-hand side is NaN) cannot make progress.
    if (flag == CV_SUCCESS && t == t_prev) {
      copy_state();
      sum.status = IntegratorStatus::failure;
      sum.message = fmt::format("CVODE: no progress at t = {:.9g} s (step size below the resolution of t; "
                                "{} right-hand side evaluations returned NaN or inf)", t, cv.ud.nonfinite_rhs);
      return failed();
    }
    dense.t_begin = t_prev;
    dense.t_end = t;
    copy_state();
    auto dense_failed = [&] {
      if (dense.flag >= 0) return false;
      check_flag(dense.flag, "CVodeGetDky", sum);
      return true;
    };
    if (flag == CV_ROOT_RETURN) {
      if (!check_flag(CVodeGetRootInfo(cv.mem, roots.data()), "CVodeGetRootInfo", sum)) return failed();
      if (observer) observer->on_step(dense);
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::event;
      for (int e = 0; e < ne; ++e)
        if (roots[e] != 0) { sum.event_index = e; break; }
      return sum;
    }
    if (observer && !observer->on_step(dense)) {
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::stopped_by_observer;
      return sum;
    }
    if (dense_failed()) return failed();
    if (flag == CV_TSTOP_RETURN || t >= t_end) {
      sum.status = IntegratorStatus::reached_end;
      return sum;
    }
  }
}

}  // namespace truss::integrators
