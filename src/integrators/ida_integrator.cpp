#include "integrators/ida_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include <fmt/format.h>
#include <ida/ida.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunmatrix/sunmatrix_band.h>

namespace truss::integrators {

namespace {

constexpr SundialsApi kIdaApi{"IDA", "an IDA step", "residual", IDAGetReturnFlagName,
                              IDA_SUCCESS, IDA_ROOT_RETURN, IDA_TSTOP_RETURN, IDA_TOO_MUCH_WORK,
                              IDAGetNumSteps, IDAGetNumErrTestFails, IDAGetRootInfo, IDAGetDky,
                              {"IDAGetNumSteps", "IDAGetNumErrTestFails", "IDAGetRootInfo", "IDAGetDky"}};

bool check_flag(int flag, const char* function, IntegratorSummary& sum) {
  return sunflags::check_flag(flag, "IDA", IDAGetReturnFlagName, function, sum);
}
bool check_null(const void* p, const char* function, IntegratorSummary& sum) {
  return sunflags::check_null(p, "IDA", function, sum);
}

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

// The SUNDIALS objects of one integrator, kept across calls, and what IDA's callbacks need (the
// solver is their user data; the system changes with every call).
class IdaSolver final : public SundialsSolver {
 public:
  IdaSolver() : SundialsSolver(kIdaApi) {}
  ~IdaSolver() override { free_problem(); }
  bool start(OdeSystem& sys, double t0, double t_end, const double* y0, const IntegratorOptions& o,
             IntegratorSummary& sum) override;
  int step(double t_end, double& t) override { return IDASolve(mem, t_end, &t, state, yp_, IDA_ONE_STEP); }
  // y: the first n_ode unknowns, in the system's order.
  void copy_state(N_Vector v, double* y) const override { std::copy_n(layout_.gather(v, layout_.w), n_ode_, y); }
  void free_problem() override;

 private:
  static int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* ud);
  static int root_fn(realtype t, N_Vector yy, N_Vector, realtype* g, void* ud);
  static int ewt_fn(N_Vector yy, N_Vector ewt, void* ud);
  static int jac_fn(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J, void* ud,
                    N_Vector rtemp, N_Vector ewt, N_Vector);
  bool create(int n_new, int n_ode_new, int lo, int up, double t0, IntegratorSummary& sum);
  void set_layout(const DaeForm& dae, int n_sys, int& lo, int& up);
  bool prepare(DaeForm& dae, double t0, double t_end, const double* y0, const IntegratorOptions& o,
               IntegratorSummary& sum, bool calc_ic, int& ic_flag);
  bool restart(double t0, double t_end, const IntegratorOptions& o, IntegratorSummary& sum);
  bool set_initial_step(const IntegratorOptions& o, double t0, double t_end, IntegratorSummary& sum);
  void rethrow();
  OdeSystem* sys_ = nullptr;
  DaeForm* dae_ = nullptr;
  Layout layout_;
  N_Vector yp_ = nullptr, id_ = nullptr;  // y' (with state: y) and the differential / algebraic flags
  SUNMatrix A_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  int n_ = -1, n_ode_ = -1;     // size of IDA's vectors and of y; -1: none
  int lower_ = -1, upper_ = -1;  // half-bandwidths of the banded solver
  bool guessed_ = false;         // the last start used the system's guess of y' and z
  double rtol_ = 0.0, atol_ = 0.0;  // the tolerances of the current start (ewt_fn)
  // The Jacobian's increments at most this fraction of an unknown's smooth length (jac_fn): the
  // difference quotient of a term ~ 1 / d^k (d the distance to the singularity, k = 1, 2) is then
  // within k % of its derivative.
  static constexpr double kSmoothFraction = 1e-2;
  std::vector<double> dq_y_, dq_yp_, dq_inc_;  // jac_fn's perturbed unknowns: values, increments
};

int IdaSolver::res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* ud) {
  auto* s = static_cast<IdaSolver*>(ud);
  CallbackState& cb = s->callbacks;
  if (cb.clock.passed_every()) return -1;  // unrecoverable: reported as IntegratorStatus::deadline
  const Layout& L = s->layout_;
  const double* w = L.gather(yy, L.w);
  double* r = L.r.data();
  bool ok = false;
  try {
    ok = s->dae_->calc_residual(t, w, L.gather(yp, L.wp), w + s->n_ode_, r);
  } catch (...) {
    cb.error = std::current_exception();
    return -1;  // unrecoverable: IDA returns IDA_RES_FAIL, the exception is rethrown
  }
  ++cb.evals;
  L.scatter(r, rr);
  const double* rp = N_VGetArrayPointer(rr);
  for (sunindextype i = 0; ok && i < N_VGetLength(rr); ++i) ok = std::isfinite(rp[i]);
  if (ok) return 0;
  ++cb.nonfinite;
  return 1;  // recoverable: IDA cuts the step
}

int IdaSolver::root_fn(realtype t, N_Vector yy, N_Vector, realtype* g, void* ud) {
  auto* s = static_cast<IdaSolver*>(ud);
  return call_events(*s->sys_, s->callbacks.error, t, s->layout_.gather(yy, s->layout_.w), g);
}

// IDA's error weights (IDAWFtolerances): ewt_i = 1 / max(f_i (rtol |w_i| + atol), 8 eps |w_i|), f_i
// the form's error factors (DaeForm::calc_error_factors; 1 without them: IDA's own weights). Near a
// bay that straightens, a frame height carries the bay's hinge offset x only to second order
// (f = 4 x / |D|, 2e-4 at the singular-configuration stop of Table 1): a height error d moves x, and
// the stop, by d / f, so the height is held to the tolerance of x. The floor keeps every weight
// above the rounding of its unknown (a few ulps from the residual and the Newton corrections), which
// no step size can beat. Returns -1 (IDA fails) where a factor is not in (0, 1].
int IdaSolver::ewt_fn(N_Vector yy, N_Vector ewt, void* ud) {
  auto* s = static_cast<IdaSolver*>(ud);
  const Layout& L = s->layout_;
  const double* y = N_VGetArrayPointer(yy);
  double* w = N_VGetArrayPointer(ewt);
  const bool scaled = s->dae_->calc_error_factors(L.gather(yy, L.w), L.r.data());
  for (std::size_t p = 0; p < L.order.size(); ++p) {
    const double f = scaled ? L.r[static_cast<std::size_t>(L.order[p])] : 1.0;
    if (!(f > 0.0 && f <= 1.0)) return -1;
    const double tol = f * (s->rtol_ * std::abs(y[p]) + s->atol_);
    w[p] = 1.0 / std::max(tol, 8.0 * std::numeric_limits<double>::epsilon() * std::abs(y[p]));
  }
  return 0;
}

// The Newton matrix dF/dw + c_j dF/dw' by forward differences, banded: the columns j, j + width,
// ... (width = lower + upper + 1) share one residual evaluation, each with IDA's increment
// (idaLsBandDQJac: max(sqrt(eps) max(|w_j|, |h w'_j|), 1 / ewt_j), of the sign of h w'_j; this
// reproduces IDA's own Jacobian to the bit) kept within kSmoothFraction of the unknown's smooth
// length (DaeForm::calc_smooth_lengths). Near a bay that straightens, the residual's mass and
// velocity terms vary like 1 / (distance to straight), a distance that falls to l_s 1e-8 (1.8e-9 m
// for Table 1) at the model's singular-configuration stop, below IDA's increment of a frame height
// (~5e-9 m): with it the difference quotients span the singularity (or cross it), the Jacobian is
// wrong by O(1), and Newton's iteration fails to converge at any step size short of the stop.
// Where the forward state is refused (a bay past straight) the group takes the backward difference.
int IdaSolver::jac_fn(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J, void* ud,
                      N_Vector rtemp, N_Vector ewt, N_Vector len_v) {
  auto* s = static_cast<IdaSolver*>(ud);
  realtype h = 0.0;
  if (IDAGetCurrentStep(s->mem, &h) < 0 || IDAGetErrWeights(s->mem, ewt) < 0) return -1;
  const int N = s->n_, width = s->lower_ + s->upper_ + 1;
  double* y = N_VGetArrayPointer(yy);
  double* dy = N_VGetArrayPointer(yp);
  const double* w = N_VGetArrayPointer(ewt);
  const double* r0 = N_VGetArrayPointer(rr);
  const double* r1 = N_VGetArrayPointer(rtemp);
  // The smooth lengths, in IDA's order (IDA's scratch vector len_v).
  double* len = N_VGetArrayPointer(len_v);
  const Layout& L = s->layout_;
  if (s->dae_->calc_smooth_lengths(L.gather(yy, L.w), L.r.data())) L.scatter(L.r.data(), len_v);
  else std::fill_n(len, N, std::numeric_limits<double>::infinity());
  const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  auto increment = [&](int j) {
    double inc = std::max(srur * std::max(std::abs(y[j]), std::abs(h * dy[j])), 1.0 / w[j]);
    inc = std::min(inc, std::max(kSmoothFraction * len[j], 4.0 * std::numeric_limits<double>::epsilon() * std::abs(y[j])));
    if (h * dy[j] < 0.0) inc = -inc;
    return (y[j] + inc) - y[j];
  };
  for (int g = 0; g < std::min(width, N); ++g) {
    for (int j = g; j < N; j += width) {
      s->dq_y_[static_cast<std::size_t>(j)] = y[j];
      s->dq_yp_[static_cast<std::size_t>(j)] = dy[j];
    }
    int flag = 1;
    for (const double sign : {1.0, -1.0}) {
      for (int j = g; j < N; j += width) {
        const double inc = sign * increment(j);
        y[j] += inc;
        dy[j] += cj * inc;
        s->dq_inc_[static_cast<std::size_t>(j)] = inc;
      }
      flag = res_fn(t, yy, yp, rtemp, ud);
      for (int j = g; j < N; j += width) {  // back to the unperturbed values
        y[j] = s->dq_y_[static_cast<std::size_t>(j)];
        dy[j] = s->dq_yp_[static_cast<std::size_t>(j)];
      }
      if (flag != 0) continue;
      for (int j = g; j < N; j += width) {
        double* col = SUNBandMatrix_Column(J, j);
        const double inv = 1.0 / s->dq_inc_[static_cast<std::size_t>(j)];
        for (int i = std::max(0, j - s->upper_); i <= std::min(N - 1, j + s->lower_); ++i) col[i - j] = inv * (r1[i] - r0[i]);
      }
      break;
    }
    if (flag != 0) return flag;  // recoverable (1): IDA cuts the step; an exception or the deadline (-1): fatal
  }
  return 0;
}

void IdaSolver::free_problem() {
  if (mem) IDAFree(&mem);
  if (ls_) SUNLinSolFree(ls_);
  ls_ = nullptr;
  if (A_) SUNMatDestroy(A_);
  A_ = nullptr;
  for (N_Vector* v : {&state, &yp_, &id_, &scratch}) {
    if (*v) N_VDestroy(*v);
    *v = nullptr;
  }
  n_ = n_ode_ = lower_ = upper_ = -1;
}

// The solver for a system of n_new unknowns (n_ode_new of them y), banded with half-bandwidths lo, up.
bool IdaSolver::create(int n_new, int n_ode_new, int lo, int up, double t0, IntegratorSummary& sum) {
  free_problem();
  const SUNContext ctx = ensure_context(sum);
  if (!ctx) return false;
  for (N_Vector* v : {&state, &yp_, &id_, &scratch}) {
    *v = N_VNew_Serial(n_new, ctx);
    if (!check_null(*v, "N_VNew_Serial", sum)) return false;
    N_VConst(0.0, *v);
  }
  mem = IDACreate(ctx);
  if (!check_null(mem, "IDACreate", sum)) return false;
  if (!check_flag(IDASetErrHandlerFn(mem, sunflags::silent, nullptr), "IDASetErrHandlerFn", sum)) return false;
  if (!check_flag(IDAInit(mem, res_fn, t0, state, yp_), "IDAInit", sum)) return false;
  if (!check_flag(IDASetUserData(mem, this), "IDASetUserData", sum)) return false;
  A_ = SUNBandMatrix(n_new, up, lo, ctx);
  if (!check_null(A_, "SUNBandMatrix", sum)) return false;
  ls_ = SUNLinSol_Band(state, A_, ctx);
  if (!check_null(ls_, "SUNLinSol_Band", sum)) return false;
  if (!check_flag(IDASetLinearSolver(mem, ls_, A_), "IDASetLinearSolver", sum)) return false;
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
  if (!check_flag(IDASetJacFn(mem, jac_fn), "IDASetJacFn", sum)) return false;
  dq_y_.assign(static_cast<std::size_t>(n_new), 0.0);
  dq_yp_ = dq_inc_ = dq_y_;
  n_ = n_new;
  n_ode_ = n_ode_new;
  lower_ = lo;
  upper_ = up;
  return true;
}

// The layout of dae's unknowns in IDA's vectors and its half-bandwidths lo, up; a form without a
// band order keeps its own order with a full band.
void IdaSolver::set_layout(const DaeForm& dae, int n_sys, int& lo, int& up) {
  Layout& L = layout_;
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

// Restart IDA on the system from (t0, y0). calc_ic: consistent z and y' by IDACalcIC (else the
// system's guess as it is); ic_flag receives IDACalcIC's flag.
bool IdaSolver::prepare(DaeForm& dae, double t0, double t_end, const double* y0, const IntegratorOptions& o,
                        IntegratorSummary& sum, bool calc_ic, int& ic_flag) {
  const int n_ode_sys = sys_->size(), n_sys = n_ode_sys + dae.num_algebraic();
  int lo = 0, up = 0;
  set_layout(dae, n_sys, lo, up);
  if ((n_sys != n_ || n_ode_sys != n_ode_ || lo != lower_ || up != upper_) && !create(n_sys, n_ode_sys, lo, up, t0, sum))
    return false;
  dae_ = &dae;
  callbacks.reset_counts();
  // (y, z) and (y', z') in the system's order, then into IDA's.
  std::vector<double> w(static_cast<std::size_t>(n_), 0.0), wp(w.size(), 0.0);
  std::copy(y0, y0 + n_ode_, w.begin());
  // The system's guess of y' and z (else zeros); IDACalcIC corrects it. From a zero guess its
  // Newton iteration (on the DQ Jacobian with the differential columns scaled by 1/h) failed to
  // converge (IDA_CONV_FAIL) at some rail entries of torque-driven runs.
  guessed_ = dae.calc_initial_guess(t0, w.data(), wp.data(), w.data() + n_ode_);
  if (!guessed_) {
    std::fill(wp.begin(), wp.end(), 0.0);
    std::fill(w.begin() + n_ode_, w.end(), 0.0);
  }
  layout_.scatter(w.data(), state);
  layout_.scatter(wp.data(), yp_);
  // Differential (1) and algebraic (0) components; the algebraic ones leave the error test.
  std::fill(w.begin(), w.end(), 0.0);
  std::fill(w.begin(), w.begin() + n_ode_, 1.0);
  layout_.scatter(w.data(), id_);
  if (!check_flag(IDASetId(mem, id_), "IDASetId", sum) || !restart(t0, t_end, o, sum)) return false;
  // Consistent start: z and the differential components of y' for the given y. tout1 only sets
  // the direction and the scale of IDACalcIC's internal step (a thousandth of the distance).
  if (calc_ic) {
    const double tout1 = std::min(t_end, t0 + (o.initial_step > 0.0 ? o.initial_step : 1e-3));
    ic_flag = IDACalcIC(mem, IDA_YA_YDP_INIT, tout1);
    if (!check_flag(ic_flag, "IDACalcIC", sum)) return false;
    if (!check_flag(IDAGetConsistentIC(mem, state, yp_), "IDAGetConsistentIC", sum)) return false;
  }
  return o.initial_step > 0.0 || set_initial_step(o, t0, t_end, sum);
}

// IDA restarted at t0 with the options and events of this call (the vectors as set).
bool IdaSolver::restart(double t0, double t_end, const IntegratorOptions& o, IntegratorSummary& sum) {
  if (!check_flag(IDAReInit(mem, t0, state, yp_), "IDAReInit", sum)) return false;
  rtol_ = o.rtol;
  atol_ = o.atol;
  if (!check_flag(IDAWFtolerances(mem, ewt_fn), "IDAWFtolerances", sum)) return false;
  if (!check_flag(IDASetMaxNumSteps(mem, o.max_steps), "IDASetMaxNumSteps", sum)) return false;
  if (!check_flag(IDASetStopTime(mem, t_end), "IDASetStopTime", sum)) return false;
  if (!check_flag(IDASetMaxStep(mem, std::isfinite(o.max_step) ? o.max_step : 0.0), "IDASetMaxStep", sum)) return false;
  if (!check_flag(IDASetInitStep(mem, o.initial_step), "IDASetInitStep", sum)) return false;
  if (!check_flag(IDARootInit(mem, 0, nullptr), "IDARootInit", sum)) return false;
  const int ne = sys_->num_events();
  if (ne == 0) return true;
  std::vector<int> dirs(static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) dirs[static_cast<std::size_t>(e)] = sys_->event_direction(e);
  return check_flag(IDARootInit(mem, ne, root_fn), "IDARootInit", sum) &&
         check_flag(IDASetRootDirection(mem, dirs.data()), "IDASetRootDirection", sum) &&
         check_flag(IDASetNoInactiveRootWarn(mem), "IDASetNoInactiveRootWarn", sum);
}

// IDA's own first step, h ||y'0||_WRMS = 1/2, is ~1e-14 s at tight atol (y' is O(1) while the
// weights are atol): 40 doublings per phase, and steps of a few ulps of t that spoil the Hermite
// refinement of the peaks (its q' is a difference quotient over the span). Hairer's first guess
// instead (Hairer, Norsett, Wanner I, II.4): h0 = 0.01 ||y0|| / ||y'0||, from the vectors as set.
bool IdaSolver::set_initial_step(const IntegratorOptions& o, double t0, double t_end, IntegratorSummary& sum) {
  std::vector<double> w(layout_.w.size()), wp(w.size());
  const double* y = layout_.gather(state, w);
  const double* dy = layout_.gather(yp_, wp);
  double d0 = 0.0, d1 = 0.0;
  for (int i = 0; i < n_ode_; ++i) {
    const double wt = o.atol + o.rtol * std::abs(y[i]);
    d0 += (y[i] / wt) * (y[i] / wt);
    d1 += (dy[i] / wt) * (dy[i] / wt);
  }
  const double h0 = d0 < 1e-10 * n_ode_ || d1 < 1e-10 * n_ode_ ? 1e-6 : 0.01 * std::sqrt(d0 / d1);
  return check_flag(IDASetInitStep(mem, std::min(h0, 0.5 * (t_end - t0))), "IDASetInitStep", sum);
}

// An exception of a callback during the start, rethrown (the objects freed first).
void IdaSolver::rethrow() {
  if (!callbacks.error) return;
  const std::exception_ptr e = callbacks.error;
  free_problem();
  std::rethrow_exception(e);
}

bool IdaSolver::start(OdeSystem& sys, double t0, double t_end, const double* y0, const IntegratorOptions& o,
                      IntegratorSummary& sum) {
  DaeForm* dae = sys.dae_form();
  if (!dae || sys.size() <= 0 || dae->num_algebraic() < 0) {
    sum.status = IntegratorStatus::failure;
    sum.message = "IDA: the system has no residual form (run.integrator = \"ida\" solves the free stack's phases)";
    return false;
  }
  sys_ = &sys;
  auto failed = [&] {
    if (callbacks.clock.hit) {
      sum.status = IntegratorStatus::deadline;
      sum.message = fmt::format("wall-clock deadline passed inside {} at t = {:.9g} s", kIdaApi.a_step, sum.t);
    }
    free_problem();  // recreated from scratch on the next call
    return false;
  };
  int ic_flag = IDA_SUCCESS;
  bool prepared = prepare(*dae, t0, t_end, y0, o, sum, true, ic_flag);
  rethrow();
  if (!prepared && !callbacks.clock.hit && ic_flag == IDA_CONV_FAIL && guessed_) {
    // At rtol ~1e-13 IDACalcIC's convergence test sits at the rounding level of the guess, which
    // the system computed consistent to rounding (the direct solve): start from the guess as it is.
    sum = IntegratorSummary{};
    sum.t = t0;
    prepared = prepare(*dae, t0, t_end, y0, o, sum, false, ic_flag);
    rethrow();
  }
  if (!prepared) return failed();
  state_size = n_ode_;
  return true;
}

}  // namespace

std::unique_ptr<SundialsSolver> make_ida_solver() { return std::make_unique<IdaSolver>(); }

}  // namespace truss::integrators
