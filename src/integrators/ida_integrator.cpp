#include "integrators/ida_integrator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <numeric>

#include <sunlinsol/sunlinsol_band.h>
#include <sunmatrix/sunmatrix_band.h>

#include "integrators/callback_deadline.hpp"
#include "integrators/sundials_checks.hpp"
#include "integrators/sundials_common.hpp"

namespace truss::integrators {

namespace {

// Where each unknown w = (y, z) of the system sits in IDA's vectors: position p holds w[order[p]]
// (the residual rows likewise).
struct Layout {
  std::vector<int> order;
  mutable std::vector<double> w, wp, r;  // the system's order (scratch of the callbacks)
  // IDA's vector -> the system's order.
  const double* gather(N_Vector v, std::vector<double>& out) const {
    const double* p = N_VGetArrayPointer(v);
    for (std::size_t k = 0; k < order.size(); ++k) out[static_cast<std::size_t>(order[k])] = p[k];
    return out.data();
  }
  void scatter(const double* in, N_Vector v) const {
    double* p = N_VGetArrayPointer(v);
    for (std::size_t k = 0; k < order.size(); ++k) p[k] = in[order[k]];
  }
};

// What IDA's callbacks need; the system changes with every integrate() call.
struct UserData {
  OdeSystem* sys = nullptr;
  DaeForm* dae = nullptr;
  int n_ode = 0;              // size of y; the algebraic unknowns z follow it in w = (y, z)
  Layout layout;
  long res_evals = 0;
  long nonfinite_res = 0;     // evaluations that returned NaN or inf (IDA retried smaller steps)
  std::exception_ptr error;   // thrown inside a callback, rethrown after IDASolve returns
  // The wall-time cap: the residual reads it every few evaluations (IDACalcIC's and the
  // difference-quotient Jacobian's included).
  CallbackDeadline clock;
};

int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* ud) {
  auto* d = static_cast<UserData*>(ud);
  if (d->clock.passed_every()) return -1;  // unrecoverable: reported as IntegratorStatus::deadline
  const Layout& L = d->layout;
  const double* w = L.gather(yy, L.w);
  double* r = L.r.data();
  bool ok = false;
  try {
    ok = d->dae->calc_residual(t, w, L.gather(yp, L.wp), w + d->n_ode, r);
  } catch (...) {
    d->error = std::current_exception();
    return -1;  // unrecoverable: IDA returns IDA_RES_FAIL, the exception is rethrown
  }
  ++d->res_evals;
  L.scatter(r, rr);
  const double* rp = N_VGetArrayPointer(rr);
  for (sunindextype i = 0; ok && i < N_VGetLength(rr); ++i) ok = std::isfinite(rp[i]);
  if (ok) return 0;
  ++d->nonfinite_res;
  return 1;  // recoverable: IDA cuts the step
}

int root_fn(realtype t, N_Vector yy, N_Vector, realtype* g, void* ud) {
  auto* d = static_cast<UserData*>(ud);
  return sundials::call_events(*d->sys, d->error, t, d->layout.gather(yy, d->layout.w), g);
}

std::string flag_name(int flag) { return sunflags::flag_name(IDAGetReturnFlagName, flag); }
bool check_flag(int flag, const char* function, IntegratorSummary& sum) {
  return sunflags::check_flag(flag, "IDA", IDAGetReturnFlagName, function, sum);
}
bool check_null(const void* p, const char* function, IntegratorSummary& sum) {
  return sunflags::check_null(p, "IDA", function, sum);
}


}  // namespace

// The SUNDIALS objects of one integrator, kept across integrate() calls.
struct IdaIntegrator::Solver {
  sundials::Context ctx;  // first: freed last
  void* mem = nullptr;
  N_Vector yy = nullptr, yp = nullptr, id = nullptr, tmp = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver ls = nullptr;
  int n = -1, n_ode = -1;  // size of IDA's vectors and of y; -1: none
  int lower = -1, upper = -1;  // half-bandwidths of the banded solver
  bool guessed = false;    // the last start used the system's guess of y' and z
  UserData ud;

  ~Solver() {
    free_problem();
  }
  void free_problem() {
    if (mem) IDAFree(&mem);
    if (ls) SUNLinSolFree(ls);
    ls = nullptr;
    if (A) SUNMatDestroy(A);
    A = nullptr;
    for (N_Vector* v : {&yy, &yp, &id, &tmp}) {
      if (*v) N_VDestroy(*v);
      *v = nullptr;
    }
    n = n_ode = lower = upper = -1;
  }

  // The solver for a system of n_new unknowns (n_ode_new of them y), banded with half-bandwidths
  // lo, up.
  bool create(int n_new, int n_ode_new, int lo, int up, double t0, IntegratorSummary& sum) {
    free_problem();
    if (!ctx.ensure("IDA", sum)) return false;
    for (N_Vector* v : {&yy, &yp, &id, &tmp}) {
      *v = N_VNew_Serial(n_new, ctx.get());
      if (!check_null(*v, "N_VNew_Serial", sum)) return false;
      N_VConst(0.0, *v);
    }
    mem = IDACreate(ctx.get());
    if (!check_null(mem, "IDACreate", sum)) return false;
    if (!check_flag(IDASetErrHandlerFn(mem, sunflags::silent, nullptr), "IDASetErrHandlerFn", sum)) return false;
    if (!check_flag(IDAInit(mem, res_fn, t0, yy, yp), "IDAInit", sum)) return false;
    if (!check_flag(IDASetUserData(mem, &ud), "IDASetUserData", sum)) return false;
    A = SUNBandMatrix(n_new, up, lo, ctx.get());
    if (!check_null(A, "SUNBandMatrix", sum)) return false;
    ls = SUNLinSol_Band(yy, A, ctx.get());
    if (!check_null(ls, "SUNLinSol_Band", sum)) return false;
    if (!check_flag(IDASetLinearSolver(mem, ls, A), "IDASetLinearSolver", sum)) return false;
    if (!check_flag(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg", sum)) return false;
    // The residual is linear in the unknowns of IDACalcIC (y' and z at fixed y): full Newton steps
    // are exact up to rounding, and the line search only fails on that rounding at tight atol
    // (IDA_LINESEARCH_FAIL at rtol 1e-12 in a rail entry).
    if (!check_flag(IDASetLineSearchOffIC(mem, SUNTRUE), "IDASetLineSearchOffIC", sum)) return false;
    // Newton iterations per step: 10 rather than IDA's 4. Near a singular configuration (a bay
    // within a few 1e-4 l_s of straight) the iteration converges, but slowly (its matrix nears
    // singular); with 4 IDA cut the step to the resolution of t and failed (IDA_CONV_FAIL) short of
    // the model's singular-configuration stop that the ODE integrators reach.
    if (!check_flag(IDASetMaxNonlinIters(mem, 10), "IDASetMaxNonlinIters", sum)) return false;
    n = n_new;
    n_ode = n_ode_new;
    lower = lo;
    upper = up;
    return true;
  }

  // The layout of dae's unknowns in IDA's vectors (ud.layout) and its half-bandwidths lo, up; a
  // form without a band order keeps its own order with a full band.
  void set_layout(const DaeForm& dae, int n_sys, int& lo, int& up) {
    Layout& L = ud.layout;
    if (!dae.find_band_order(L.order, lo, up) || static_cast<int>(L.order.size()) != n_sys) {
      L.order.resize(static_cast<std::size_t>(n_sys));
      std::iota(L.order.begin(), L.order.end(), 0);
      lo = up = n_sys - 1;
    }
    lo = std::min(lo, n_sys - 1);
    up = std::min(up, n_sys - 1);
    L.w.assign(static_cast<std::size_t>(n_sys), 0.0);
    L.wp.assign(L.w.size(), 0.0);
    L.r.assign(L.w.size(), 0.0);
  }

  // Restart IDA on sys from (t0, y0). calc_ic: consistent z and y' by IDACalcIC (else the system's
  // guess as it is); ic_flag receives IDACalcIC's flag.
  bool prepare(OdeSystem& sys, DaeForm& dae, double t0, double t_end, const double* y0,
               const IntegratorOptions& o, IntegratorSummary& sum, bool calc_ic, int& ic_flag) {
    const int n_ode_sys = sys.size(), n_sys = n_ode_sys + dae.num_algebraic();
    int lo = 0, up = 0;
    set_layout(dae, n_sys, lo, up);
    if ((n_sys != n || n_ode_sys != n_ode || lo != lower || up != upper) && !create(n_sys, n_ode_sys, lo, up, t0, sum))
      return false;
    ud.sys = &sys;
    ud.dae = &dae;
    ud.n_ode = n_ode;
    ud.res_evals = 0;
    ud.nonfinite_res = 0;
    ud.error = nullptr;
    // (y, z) and (y', z') in the system's order, then into IDA's.
    std::vector<double> w(static_cast<std::size_t>(n), 0.0), wp(w.size(), 0.0);
    std::copy(y0, y0 + n_ode, w.begin());
    // The system's guess of y' and z (else zeros); IDACalcIC corrects it. From a zero guess its
    // Newton iteration (on the DQ Jacobian with the differential columns scaled by 1/h) failed to
    // converge (IDA_CONV_FAIL) at some rail entries of torque-driven runs.
    guessed = dae.calc_initial_guess(t0, w.data(), wp.data(), w.data() + n_ode);
    if (!guessed) {
      std::fill(wp.begin(), wp.end(), 0.0);
      std::fill(w.begin() + n_ode, w.end(), 0.0);
    }
    ud.layout.scatter(w.data(), yy);
    ud.layout.scatter(wp.data(), yp);
    // Differential (1) and algebraic (0) components; the algebraic ones leave the error test.
    std::fill(w.begin(), w.end(), 0.0);
    std::fill(w.begin(), w.begin() + n_ode, 1.0);
    ud.layout.scatter(w.data(), id);
    if (!check_flag(IDASetId(mem, id), "IDASetId", sum)) return false;
    if (!check_flag(IDAReInit(mem, t0, yy, yp), "IDAReInit", sum)) return false;
    if (!check_flag(IDASStolerances(mem, o.rtol, o.atol), "IDASStolerances", sum)) return false;
    if (!check_flag(IDASetMaxNumSteps(mem, o.max_steps), "IDASetMaxNumSteps", sum)) return false;
    if (!check_flag(IDASetStopTime(mem, t_end), "IDASetStopTime", sum)) return false;
    if (!check_flag(IDASetMaxStep(mem, std::isfinite(o.max_step) ? o.max_step : 0.0), "IDASetMaxStep", sum)) return false;
    if (!check_flag(IDASetInitStep(mem, o.initial_step), "IDASetInitStep", sum)) return false;
    if (!check_flag(IDARootInit(mem, 0, nullptr), "IDARootInit", sum)) return false;
    const int ne = sys.num_events();
    if (ne > 0) {
      if (!check_flag(IDARootInit(mem, ne, root_fn), "IDARootInit", sum)) return false;
      std::vector<int> dirs(static_cast<std::size_t>(ne));
      for (int e = 0; e < ne; ++e) dirs[static_cast<std::size_t>(e)] = sys.event_direction(e);
      if (!check_flag(IDASetRootDirection(mem, dirs.data()), "IDASetRootDirection", sum)) return false;
      if (!check_flag(IDASetNoInactiveRootWarn(mem), "IDASetNoInactiveRootWarn", sum)) return false;
    }
    // Consistent start: z and the differential components of y' for the given y. tout1 only sets
    // the direction and the scale of IDACalcIC's internal step (a thousandth of the distance).
    if (calc_ic) {
      const double tout1 = std::min(t_end, t0 + (o.initial_step > 0.0 ? o.initial_step : 1e-3));
      ic_flag = IDACalcIC(mem, IDA_YA_YDP_INIT, tout1);
      if (!check_flag(ic_flag, "IDACalcIC", sum)) return false;
      if (!check_flag(IDAGetConsistentIC(mem, yy, yp), "IDAGetConsistentIC", sum)) return false;
    }
    return o.initial_step > 0.0 || set_initial_step(o, t0, t_end, sum);
  }

  // IDA's own first step, h ||y'0||_WRMS = 1/2, is ~1e-14 s at tight atol (y' is O(1) while the
  // weights are atol): 40 doublings per phase, and steps of a few ulps of t that spoil the Hermite
  // refinement of the peaks (its q' is a difference quotient over the span). Hairer's first guess
  // instead (Hairer, Norsett, Wanner I, II.4): h0 = 0.01 ||y0|| / ||y'0||, from yy, yp as set.
  bool set_initial_step(const IntegratorOptions& o, double t0, double t_end, IntegratorSummary& sum) {
    std::vector<double> w(ud.layout.w.size()), wp(w.size());
    const double* y = ud.layout.gather(yy, w);
    const double* dy = ud.layout.gather(yp, wp);
    double d0 = 0.0, d1 = 0.0;
    for (int i = 0; i < n_ode; ++i) {
      const double w = o.atol + o.rtol * std::abs(y[i]);
      d0 += (y[i] / w) * (y[i] / w);
      d1 += (dy[i] / w) * (dy[i] / w);
    }
    const double h0 = d0 < 1e-10 * n_ode || d1 < 1e-10 * n_ode ? 1e-6 : 0.01 * std::sqrt(d0 / d1);
    return check_flag(IDASetInitStep(mem, std::min(h0, 0.5 * (t_end - t0))), "IDASetInitStep", sum);
  }
};

IdaIntegrator::IdaIntegrator(const IntegratorOptions& opts) : opts_(opts) {}
IdaIntegrator::~IdaIntegrator() = default;

IntegratorSummary IdaIntegrator::integrate(OdeSystem& sys, double t0, double t_end, double* y0,
                                           StepObserver* observer) {
  IntegratorSummary sum;
  sum.t = t0;
  if (const std::string bad = opts_.validate(); !bad.empty()) {
    sum.status = IntegratorStatus::failure;
    sum.message = "invalid integrator options: " + bad;
    return sum;
  }
  if (!(t_end > t0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  DaeForm* dae = sys.dae_form();
  if (!dae || sys.size() <= 0 || dae->num_algebraic() < 0) {
    sum.status = IntegratorStatus::failure;
    sum.message = "IDA: the system has no residual form (run.integrator = \"ida\" solves the free stack's phases)";
    return sum;
  }
  if (!solver_) solver_ = std::make_unique<Solver>();
  Solver& s = *solver_;
  auto failed = [&] {
    s.free_problem();  // recreated from scratch on the next call
    return sum;
  };
  auto rethrow = [&] {
    if (!s.ud.error) return;
    const std::exception_ptr e = s.ud.error;
    s.free_problem();
    std::rethrow_exception(e);
  };
  s.ud.clock.reset(observer ? observer->deadline() : std::chrono::steady_clock::time_point::max());
  auto past_deadline = [&] {
    if (!s.ud.clock.hit) return false;
    sum.status = IntegratorStatus::deadline;
    sum.message = fmt::format("wall-clock deadline passed inside an IDA step at t = {:.9g} s", sum.t);
    return true;
  };
  int ic_flag = IDA_SUCCESS;
  bool prepared = s.prepare(sys, *dae, t0, t_end, y0, opts_, sum, true, ic_flag);
  rethrow();
  if (!prepared && past_deadline()) return failed();
  if (!prepared && ic_flag == IDA_CONV_FAIL && s.guessed) {
    // At rtol ~1e-13 IDACalcIC's convergence test sits at the rounding level of the guess, which
    // the system computed consistent to rounding (the direct solve): start from the guess as it is.
    sum = IntegratorSummary{};
    sum.t = t0;
    prepared = s.prepare(sys, *dae, t0, t_end, y0, opts_, sum, false, ic_flag);
    rethrow();
  }
  if (!prepared) {
    past_deadline();
    return failed();
  }
  const int ne = sys.num_events();
  auto copy_state = [&] {
    const double* p = s.ud.layout.gather(s.yy, s.ud.layout.w);
    for (int i = 0; i < s.n_ode; ++i) y0[i] = p[i];
  };
  // Dense output of y (the first n_ode unknowns, in the system's order).
  const Layout& layout = s.ud.layout;
  const int n_ode = s.n_ode;
  sundials::Dense dense(IDAGetDky, s.mem, s.tmp, n_ode, [&layout, n_ode](N_Vector v, double* y) {
    std::copy_n(layout.gather(v, layout.w), n_ode, y);
  });
  double t = t0;
  std::vector<int> roots(static_cast<std::size_t>(ne));
  while (true) {
    // The call's step budget (IDASetMaxNumSteps counts per IDASolve call, one step each here).
    if (sum.steps >= opts_.max_steps) {
      sum.status = IntegratorStatus::step_limit;
      sum.message = fmt::format("step limit of {} reached", opts_.max_steps);
      return sum;
    }
    const double t_prev = t;
    const int flag = IDASolve(s.mem, t_end, &t, s.yy, s.yp, IDA_ONE_STEP);
    rethrow();
    long steps = 0, fails = 0;
    if (!check_flag(IDAGetNumSteps(s.mem, &steps), "IDAGetNumSteps", sum)) return failed();
    if (!check_flag(IDAGetNumErrTestFails(s.mem, &fails), "IDAGetNumErrTestFails", sum)) return failed();
    sum.steps = steps;
    sum.rejected_steps = fails;
    sum.rhs_evals = s.ud.res_evals;
    sum.t = t;
    copy_state();
    if (flag < 0 && past_deadline()) return failed();
    if (flag < 0) {
      sum.status = flag == IDA_TOO_MUCH_WORK ? IntegratorStatus::step_limit : IntegratorStatus::failure;
      sum.message = fmt::format("IDA flag {} ({}) at t = {:.9g} s ({} residual evaluations returned NaN or inf)",
                                flag, flag_name(flag), t, s.ud.nonfinite_res);
      return failed();
    }
    if (flag == IDA_SUCCESS && t == t_prev) {
      sum.status = IntegratorStatus::failure;
      sum.message = fmt::format("IDA: no progress at t = {:.9g} s (step size below the resolution of t)", t);
      return failed();
    }
    dense.t_begin = t_prev;
    dense.t_end = t;
    auto dense_failed = [&] { return dense.flag < 0 && !check_flag(dense.flag, "IDAGetDky", sum); };
    if (flag == IDA_ROOT_RETURN) {
      if (!check_flag(IDAGetRootInfo(s.mem, roots.data()), "IDAGetRootInfo", sum)) return failed();
      if (observer) observer->on_step(dense);
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::event;
      for (int e = 0; e < ne; ++e)
        if (roots[static_cast<std::size_t>(e)] != 0) { sum.event_index = e; break; }
      return sum;
    }
    if (observer && !observer->on_step(dense)) {
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::stopped_by_observer;
      return sum;
    }
    if (dense_failed()) return failed();
    if (flag == IDA_TSTOP_RETURN || t >= t_end) {
      sum.status = IntegratorStatus::reached_end;
      return sum;
    }
  }
}

}  // namespace truss::integrators
