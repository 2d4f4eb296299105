#include "integrators/sundials_integrator.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include <fmt/format.h>

namespace truss::integrators {

namespace {

// The solver's interpolant over its last step, get_dky of order 0 into the solver's scratch
// vector, then its state. Where get_dky fails, y is NaN and the first failed flag of the step is
// kept in `flag` for the loop to check after the observer.
class Dense final : public DenseOutput {
 public:
  explicit Dense(const SundialsSolver& s) : s_(s) {}
  mutable int flag = 0;
  void calc_state(double t, double* y) const override {
    const int f = s_.api().get_dky(s_.mem, t, 0, s_.scratch);
    if (f < 0) {
      std::fill_n(y, s_.state_size, std::numeric_limits<double>::quiet_NaN());
      if (flag >= 0) flag = f;
      return;
    }
    s_.copy_state(s_.scratch, y);
  }

 private:
  const SundialsSolver& s_;
};

}  // namespace

SUNContext SundialsSolver::ensure_context(IntegratorSummary& sum) {
  if (!context_.ctx &&
      !sunflags::check_sundials(SUNContext_Create(nullptr, &context_.ctx), api_.solver, "SUNContext_Create", sum))
    return nullptr;
  return context_.ctx;
}

SundialsIntegrator::SundialsIntegrator(const IntegratorOptions& opts, std::unique_ptr<SundialsSolver> solver)
    : opts_(opts), solver_(std::move(solver)) {}

IntegratorSummary SundialsIntegrator::integrate(OdeSystem& sys, double t0, double t_end, double* y,
                                               StepObserver* observer) {
  IntegratorSummary sum;
  sum.t = t0;
  if (const std::string bad = opts_.validate(); !bad.empty()) {
    sum.status = IntegratorStatus::failure;
    sum.message = "invalid integrator options: " + bad;
    return sum;
  }
  if (!(t_end > t0)) {
    sum.status = IntegratorStatus::reached_end;
    return sum;
  }
  solver_->callbacks.reset(observer ? observer->deadline() : std::chrono::steady_clock::time_point::max());
  if (!solver_->start(sys, t0, t_end, y, opts_, sum)) return sum;
  return run_steps(t0, t_end, sys.num_events(), y, observer, sum);
}

// The step loop: one step per call until an event, the end, the observer's stop, the step budget
// or a failure.
IntegratorSummary SundialsIntegrator::run_steps(double t0, double t_end, int num_events, double* y,
                                                StepObserver* observer, IntegratorSummary sum) {
  SundialsSolver& s = *solver_;
  const SundialsApi& api = s.api();
  auto check = [&](int flag, int fn) { return sunflags::check_flag(flag, api.solver, api.flag_name, api.names[fn], sum); };
  auto failed = [&] {
    s.free_problem();
    return sum;
  };
  Dense dense(s);
  std::vector<int> roots(static_cast<std::size_t>(num_events));
  double t = t0;
  while (true) {
    // The step budget of the call: the solvers' own maximum counts steps per call of theirs, and
    // in ONE_STEP mode every call takes one step.
    if (sum.steps >= opts_.max_steps) {
      sum.status = IntegratorStatus::step_limit;
      sum.message = fmt::format("step limit of {} reached", opts_.max_steps);
      return sum;
    }
    const double t_prev = t;
    const int flag = s.step(t_end, t);
    if (s.callbacks.error) {
      const std::exception_ptr e = s.callbacks.error;
      s.free_problem();
      std::rethrow_exception(e);
    }
    long steps = 0, fails = 0;
    if (!check(api.get_num_steps(s.mem, &steps), 0) || !check(api.get_num_err_test_fails(s.mem, &fails), 1))
      return failed();
    sum.steps = steps;
    sum.rejected_steps = fails;
    sum.rhs_evals = s.callbacks.evals;
    sum.t = t;
    s.copy_state(s.state, y);
    if (flag < 0 && s.callbacks.clock.hit) {
      sum.status = IntegratorStatus::deadline;
      sum.message = fmt::format("wall-clock deadline passed inside {} at t = {:.9g} s", api.a_step, t);
      return failed();
    }
    if (flag < 0) {
      sum.status = flag == api.too_much_work ? IntegratorStatus::step_limit : IntegratorStatus::failure;
      sum.message = fmt::format("{} flag {} ({}) at t = {:.9g} s ({} {} evaluations returned NaN or inf)", api.solver,
                                flag, sunflags::flag_name(api.flag_name, flag), t, s.callbacks.nonfinite,
                                api.evaluation);
      return failed();
    }
    // A step that left t unchanged (t + h == t: the step size fell below the resolution of t,
    // typically at the edge of a region where the equations give NaN) cannot make progress.
    if (flag == api.success && t == t_prev) {
      sum.status = IntegratorStatus::failure;
      sum.message = fmt::format("{}: no progress at t = {:.9g} s (step size below the resolution of t; {} {} "
                                "evaluations returned NaN or inf)", api.solver, t, s.callbacks.nonfinite,
                                api.evaluation);
      return failed();
    }
    dense.t_begin = t_prev;
    dense.t_end = t;
    auto dense_failed = [&] { return dense.flag < 0 && !check(dense.flag, 3); };
    if (flag == api.root_return) {
      if (!check(api.get_root_info(s.mem, roots.data()), 2)) return failed();
      if (observer) observer->on_step(dense);
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::event;
      const auto e = std::find_if(roots.begin(), roots.end(), [](int r) { return r != 0; });
      if (e != roots.end()) sum.event_index = static_cast<int>(e - roots.begin());
      return sum;
    }
    if (observer && !observer->on_step(dense)) {
      if (dense_failed()) return failed();
      sum.status = IntegratorStatus::stopped_by_observer;
      return sum;
    }
    if (dense_failed()) return failed();
    if (flag == api.tstop_return || t >= t_end) {
      sum.status = IntegratorStatus::reached_end;
      return sum;
    }
  }
}

}  // namespace truss::integrators
