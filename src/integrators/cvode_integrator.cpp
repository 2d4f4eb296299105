#include "integrators/cvode_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <cvode/cvode.h>
#include <fmt/format.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include "integrators/cvode_dense_lu.hpp"

namespace truss::integrators {

namespace {

constexpr SundialsApi kCvodeApi{"CVODE", "a CVODE step", "right-hand side", CVodeGetReturnFlagName,
                                CV_SUCCESS, CV_ROOT_RETURN, CV_TSTOP_RETURN, CV_TOO_MUCH_WORK,
                                CVodeGetNumSteps, CVodeGetNumErrTestFails, CVodeGetRootInfo, CVodeGetDky,
                                {"CVodeGetNumSteps", "CVodeGetNumErrTestFails", "CVodeGetRootInfo", "CVodeGetDky"}};

bool check_flag(int flag, const char* function, IntegratorSummary& sum) {
  return sunflags::check_flag(flag, "CVODE", CVodeGetReturnFlagName, function, sum);
}
bool check_null(const void* p, const char* function, IntegratorSummary& sum) {
  return sunflags::check_null(p, "CVODE", function, sum);
}

// The SUNDIALS objects of one integrator, kept across calls, and what CVODE's callbacks need (the
// solver is their user data; the system changes with every call).
class CvodeSolver final : public SundialsSolver {
 public:
  explicit CvodeSolver(CvodeMethod method) : SundialsSolver(kCvodeApi), method_(method) {}
  ~CvodeSolver() override { free_problem(); }
  bool start(OdeSystem& sys, double t0, double t_end, const double* y0, const IntegratorOptions& o,
             IntegratorSummary& sum) override;
  int step(double t_end, double& t) override { return CVode(mem, t_end, state, &t, CV_ONE_STEP); }
  void copy_state(N_Vector v, double* y) const override { std::copy_n(N_VGetArrayPointer(v), n_, y); }
  void free_problem() override;

 private:
  static int rhs_fn(realtype t, N_Vector y, N_Vector ydot, void* ud);
  static int jac_fn(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* ud, N_Vector ftemp, N_Vector, N_Vector);
  static int root_fn(realtype t, N_Vector y, realtype* g, void* ud);
  bool create(int n_new, double t0, IntegratorSummary& sum);
  bool restart(double t0, double t_end, const double* y0, const IntegratorOptions& o, IntegratorSummary& sum);
  CvodeMethod method_;
  OdeSystem* sys_ = nullptr;
  N_Vector ewt_ = nullptr;             // scratch for the error weights (the Jacobian)
  SUNNonlinearSolver nls_ = nullptr;   // adams: fixed point (bdf: CVODE's own Newton solver)
  SUNMatrix A_ = nullptr;              // bdf: dense Newton matrix
  SUNLinearSolver ls_ = nullptr;       // bdf: dense LU
  int n_ = -1;                         // size of the vectors and the CVODE memory; -1: none
};

int CvodeSolver::rhs_fn(realtype t, N_Vector y, N_Vector ydot, void* ud) {
  auto* s = static_cast<CvodeSolver*>(ud);
  CallbackState& cb = s->callbacks;
  if (cb.clock.passed_every()) return -1;  // unrecoverable: CVode returns, reported as IntegratorStatus::deadline
  try {
    s->sys_->calc_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  } catch (...) {
    cb.error = std::current_exception();
    return -1;  // unrecoverable: CVode returns CV_RHSFUNC_FAIL, the exception is rethrown
  }
  ++cb.evals;
  for (sunindextype i = 0; i < N_VGetLength(ydot); ++i)
    if (!std::isfinite(N_VGetArrayPointer(ydot)[i])) {
      ++cb.nonfinite;
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
int CvodeSolver::jac_fn(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* ud, N_Vector ftemp, N_Vector, N_Vector) {
  auto* s = static_cast<CvodeSolver*>(ud);
  realtype h = 0.0;
  if (CVodeGetCurrentStep(s->mem, &h) < 0 || CVodeGetErrWeights(s->mem, s->ewt_) < 0) return -1;
  const sunindextype n = N_VGetLength(y);
  const double eps = std::numeric_limits<double>::epsilon(), srur = std::sqrt(eps);
  const double fnorm = N_VWrmsNorm(fy, s->ewt_);
  const double min_inc = fnorm != 0.0 ? 1000.0 * std::abs(h) * eps * static_cast<double>(n) * fnorm : 1.0;
  double* yd = N_VGetArrayPointer(y);
  const double* w = N_VGetArrayPointer(s->ewt_);
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

int CvodeSolver::root_fn(realtype t, N_Vector y, realtype* g, void* ud) {
  auto* s = static_cast<CvodeSolver*>(ud);
  return call_events(*s->sys_, s->callbacks.error, t, N_VGetArrayPointer(y), g);
}

// Everything but the context (in the order of the SUNDIALS examples).
void CvodeSolver::free_problem() {
  if (mem) CVodeFree(&mem);
  if (nls_) SUNNonlinSolFree(nls_);
  nls_ = nullptr;
  if (ls_) SUNLinSolFree(ls_);
  ls_ = nullptr;
  if (A_) SUNMatDestroy(A_);
  A_ = nullptr;
  for (N_Vector* v : {&state, &scratch, &ewt_}) {
    if (*v) N_VDestroy(*v);
    *v = nullptr;
  }
  n_ = -1;
}

// CVODE memory, vectors and the method's solvers for systems of size n_new.
bool CvodeSolver::create(int n_new, double t0, IntegratorSummary& sum) {
  free_problem();
  const SUNContext ctx = ensure_context(sum);
  if (!ctx) return false;
  for (N_Vector* v : {&state, &scratch, &ewt_}) {
    *v = N_VNew_Serial(n_new, ctx);
    if (!check_null(*v, "N_VNew_Serial", sum)) return false;
  }
  N_VConst(0.0, state);
  mem = CVodeCreate(method_ == CvodeMethod::bdf ? CV_BDF : CV_ADAMS, ctx);
  if (!check_null(mem, "CVodeCreate", sum)) return false;
  if (!check_flag(CVodeSetErrHandlerFn(mem, sunflags::silent, nullptr), "CVodeSetErrHandlerFn", sum)) return false;
  if (!check_flag(CVodeInit(mem, rhs_fn, t0, state), "CVodeInit", sum)) return false;
  if (!check_flag(CVodeSetUserData(mem, this), "CVodeSetUserData", sum)) return false;
  if (method_ == CvodeMethod::bdf) {
    // Newton (CVODE's default nonlinear solver) on a dense matrix; difference quotients (jac_fn)
    // cost n extra right-hand sides per Jacobian.
    A_ = SUNDenseMatrix(n_new, n_new, ctx);
    if (!check_null(A_, "SUNDenseMatrix", sum)) return false;
    ls_ = make_cvode_dense_lu(ctx, &callbacks.clock);  // SUNLinSol_Dense's LU, stoppable at the wall-time cap
    if (!check_null(ls_, "SUNLinSolNewEmpty", sum)) return false;
    if (!check_flag(CVodeSetLinearSolver(mem, ls_, A_), "CVodeSetLinearSolver", sum)) return false;
    if (!check_flag(CVodeSetJacFn(mem, jac_fn), "CVodeSetJacFn", sum)) return false;
  } else {
    nls_ = SUNNonlinSol_FixedPoint(state, 0, ctx);
    if (!check_null(nls_, "SUNNonlinSol_FixedPoint", sum)) return false;
    if (!check_flag(CVodeSetNonlinearSolver(mem, nls_), "CVodeSetNonlinearSolver", sum)) return false;
    if (!check_flag(CVodeSetMaxOrd(mem, 12), "CVodeSetMaxOrd", sum)) return false;
  }
  n_ = n_new;
  return true;
}

// CVODE restarted from (t0, y0) with the options and events of this call.
bool CvodeSolver::restart(double t0, double t_end, const double* y0, const IntegratorOptions& o, IntegratorSummary& sum) {
  std::copy_n(y0, n_, N_VGetArrayPointer(state));
  // History, order, step counters and initial step choice start afresh.
  if (!check_flag(CVodeReInit(mem, t0, state), "CVodeReInit", sum)) return false;
  if (!check_flag(CVodeSStolerances(mem, o.rtol, o.atol), "CVodeSStolerances", sum)) return false;
  if (!check_flag(CVodeSetMaxNumSteps(mem, o.max_steps), "CVodeSetMaxNumSteps", sum)) return false;
  // After CVodeReInit (CVodeSetStopTime checks tstop against the current step once nst > 0).
  if (!check_flag(CVodeSetStopTime(mem, t_end), "CVodeSetStopTime", sum)) return false;
  // 0 restores CVODE's defaults: no cap, CVODE's own initial step estimate.
  if (!check_flag(CVodeSetMaxStep(mem, std::isfinite(o.max_step) ? o.max_step : 0.0), "CVodeSetMaxStep", sum))
    return false;
  if (!check_flag(CVodeSetInitStep(mem, o.initial_step), "CVodeSetInitStep", sum)) return false;
  // Root functions: dropped and allocated again, so that directions and the inactive-root flags of
  // the last call do not carry over (CVodeRootInit with an unchanged count keeps them).
  if (!check_flag(CVodeRootInit(mem, 0, nullptr), "CVodeRootInit", sum)) return false;
  const int ne = sys_->num_events();
  if (ne == 0) return true;
  std::vector<int> dirs(static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) dirs[static_cast<std::size_t>(e)] = sys_->event_direction(e);
  return check_flag(CVodeRootInit(mem, ne, root_fn), "CVodeRootInit", sum) &&
         check_flag(CVodeSetRootDirection(mem, dirs.data()), "CVodeSetRootDirection", sum) &&
         check_flag(CVodeSetNoInactiveRootWarn(mem), "CVodeSetNoInactiveRootWarn", sum);
}

bool CvodeSolver::start(OdeSystem& sys, double t0, double t_end, const double* y0, const IntegratorOptions& o,
                        IntegratorSummary& sum) {
  if (sys.size() <= 0) {
    sum.status = IntegratorStatus::failure;
    sum.message = fmt::format("CVODE: system size must be positive, got {}", sys.size());
    return false;
  }
  sys_ = &sys;
  if ((sys.size() != n_ && !create(sys.size(), t0, sum)) || !restart(t0, t_end, y0, o, sum)) {
    free_problem();  // start from new SUNDIALS objects next time
    return false;
  }
  state_size = n_;
  return true;
}

}  // namespace

std::unique_ptr<SundialsSolver> make_cvode_solver(CvodeMethod method) { return std::make_unique<CvodeSolver>(method); }

}  // namespace truss::integrators
