#include "integrators/cvode_integrator.hpp"

#include <cmath>
#include <vector>

#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

namespace truss::integrators {

namespace {

struct UserData {
  OdeSystem* sys;
  long rhs_evals = 0;
};

int rhs_fn(realtype t, N_Vector y, N_Vector ydot, void* ud) {
  auto* d = static_cast<UserData*>(ud);
  d->sys->calc_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  ++d->rhs_evals;
  for (sunindextype i = 0; i < N_VGetLength(ydot); ++i)
    if (!std::isfinite(N_VGetArrayPointer(ydot)[i])) return 1;  // recoverable: CVODE cuts the step
  return 0;
}

int root_fn(realtype t, N_Vector y, realtype* g, void* ud) {
  static_cast<UserData*>(ud)->sys->calc_events(t, N_VGetArrayPointer(y), g);
  return 0;
}

void silent(int, const char*, const char*, char*, void*) {}

class CvodeDense : public DenseOutput {
 public:
  void* mem = nullptr;
  N_Vector tmp = nullptr;
  void calc_state(double t, double* y) const override {
    CVodeGetDky(mem, t, 0, tmp);
    const double* p = N_VGetArrayPointer(tmp);
    for (sunindextype i = 0; i < N_VGetLength(tmp); ++i) y[i] = p[i];
  }
};

// RAII holder for the SUNDIALS objects of one integration.
struct Cvode {
  SUNContext ctx = nullptr;
  void* mem = nullptr;
  N_Vector y = nullptr, tmp = nullptr;
  SUNNonlinearSolver nls = nullptr;
  ~Cvode() {
    if (nls) SUNNonlinSolFree(nls);
    if (y) N_VDestroy(y);
    if (tmp) N_VDestroy(tmp);
    if (mem) CVodeFree(&mem);
    if (ctx) SUNContext_Free(&ctx);
  }
};

}  // namespace

IntegratorSummary CvodeIntegrator::integrate(OdeSystem& sys, double t0, double t_end, double* y0,
                                             StepObserver* observer) {
  IntegratorSummary sum;
  sum.t = t0;
  if (!(t_end > t0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  const int n = sys.size();
  Cvode cv;
  UserData ud{&sys};
  auto fail = [&](const char* what) {
    sum.status = IntegratorStatus::failure;
    sum.message = fmt::format("CVODE: {} failed", what);
    return sum;
  };
  if (SUNContext_Create(nullptr, &cv.ctx) != 0) return fail("SUNContext_Create");
  cv.y = N_VNew_Serial(n, cv.ctx);
  cv.tmp = N_VNew_Serial(n, cv.ctx);
  for (int i = 0; i < n; ++i) N_VGetArrayPointer(cv.y)[i] = y0[i];
  cv.mem = CVodeCreate(CV_ADAMS, cv.ctx);
  if (!cv.mem) return fail("CVodeCreate");
  CVodeSetErrHandlerFn(cv.mem, silent, nullptr);
  if (CVodeInit(cv.mem, rhs_fn, t0, cv.y) != CV_SUCCESS) return fail("CVodeInit");
  CVodeSStolerances(cv.mem, opts_.rtol, opts_.atol);
  CVodeSetUserData(cv.mem, &ud);
  cv.nls = SUNNonlinSol_FixedPoint(cv.y, 0, cv.ctx);
  CVodeSetNonlinearSolver(cv.mem, cv.nls);
  CVodeSetMaxNumSteps(cv.mem, opts_.max_steps);
  CVodeSetStopTime(cv.mem, t_end);
  CVodeSetMaxOrd(cv.mem, 12);
  if (std::isfinite(opts_.max_step)) CVodeSetMaxStep(cv.mem, opts_.max_step);
  if (opts_.initial_step > 0.0) CVodeSetInitStep(cv.mem, opts_.initial_step);
  const int ne = sys.num_events();
  std::vector<int> dirs(ne);
  if (ne > 0) {
    CVodeRootInit(cv.mem, ne, root_fn);
    for (int e = 0; e < ne; ++e) dirs[e] = sys.event_direction(e);
    CVodeSetRootDirection(cv.mem, dirs.data());
    CVodeSetNoInactiveRootWarn(cv.mem);
  }
  CvodeDense dense;
  dense.mem = cv.mem;
  dense.tmp = cv.tmp;
  double t = t0;
  std::vector<int> roots(ne);
  while (true) {
    double t_prev = t;
    const int flag = CVode(cv.mem, t_end, cv.y, &t, CV_ONE_STEP);
    long steps = 0, fails = 0;
    CVodeGetNumSteps(cv.mem, &steps);
    CVodeGetNumErrTestFails(cv.mem, &fails);
    sum.steps = steps;
    sum.rejected_steps = fails;
    sum.rhs_evals = ud.rhs_evals;
    sum.t = t;
    if (flag < 0) {
      const double* p = N_VGetArrayPointer(cv.y);
      for (int i = 0; i < n; ++i) y0[i] = p[i];
      sum.status = flag == CV_TOO_MUCH_WORK ? IntegratorStatus::step_limit : IntegratorStatus::failure;
      sum.message = fmt::format("CVODE flag {} ({}) at t = {:.9g} s", flag, CVodeGetReturnFlagName(flag), t);
      return sum;
    }
    dense.t_begin = t_prev;
    dense.t_end = t;
    const double* p = N_VGetArrayPointer(cv.y);
    for (int i = 0; i < n; ++i) y0[i] = p[i];
    if (flag == CV_ROOT_RETURN) {
      CVodeGetRootInfo(cv.mem, roots.data());
      if (observer) observer->on_step(dense);
      sum.status = IntegratorStatus::event;
      for (int e = 0; e < ne; ++e)
        if (roots[e] != 0) { sum.event_index = e; break; }
      return sum;
    }
    if (observer && !observer->on_step(dense)) {
      sum.status = IntegratorStatus::stopped_by_observer;
      return sum;
    }
    if (flag == CV_TSTOP_RETURN || t >= t_end) {
      sum.status = IntegratorStatus::reached_end;
      return sum;
    }
  }
}

}  // namespace truss::integrators
