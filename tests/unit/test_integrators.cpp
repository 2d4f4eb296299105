// The integrators on small problems with known answers: one CvodeIntegrator reused over systems
// of different sizes and events gives the same bits as fresh integrators; accuracy against the
// harmonic oscillator's closed form; event times; invalid options; a NaN right-hand side.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>
#include <stdexcept>
#include <string>
#include <vector>

#include <cvode/cvode.h>
#include <ida/ida.h>

#include "integrators/sundials_checks.hpp"
#include "integrators/cvode_integrator.hpp"
#include "integrators/dopri54.hpp"

using namespace truss::integrators;
using Catch::Matchers::Contains;
using Catch::Matchers::Matches;

namespace {

constexpr double kPi = std::numbers::pi;

// y0' = y1, y1' = -y0 - c y1 (+ y2' = y0^2 when n = 3). Events: a list of (kind, direction),
// kind 0: g = y0, kind 1: g = y2 - 0.5 (n = 3 only).
class TestSystem : public OdeSystem {
 public:
  struct Event { int kind, direction; };
  TestSystem(int n, double damping, std::vector<Event> events) : n_(n), c_(damping), ev_(std::move(events)) {}
  int size() const override { return n_; }
  void calc_rhs(double, const double* y, double* dy) override {
    dy[0] = y[1];
    dy[1] = -y[0] - c_ * y[1];
    if (n_ == 3) dy[2] = y[0] * y[0];
  }
  int num_events() const override { return static_cast<int>(ev_.size()); }
  void calc_events(double, const double* y, double* g) override {
    for (std::size_t k = 0; k < ev_.size(); ++k) g[k] = ev_[k].kind == 0 ? y[0] : y[2] - 0.5;
  }
  int event_direction(int k) const override { return ev_[static_cast<std::size_t>(k)].direction; }

 private:
  int n_;
  double c_;
  std::vector<Event> ev_;
};

// Records every accepted step: its interval and the dense output at its middle and end.
class Recorder : public StepObserver {
 public:
  explicit Recorder(int n) : n_(n) {}
  std::vector<double> trace;
  bool on_step(const DenseOutput& d) override {
    std::vector<double> y(static_cast<std::size_t>(n_));
    trace.push_back(d.t_begin);
    trace.push_back(d.t_end);
    for (double t : {0.5 * (d.t_begin + d.t_end), d.t_end}) {
      d.calc_state(t, y.data());
      trace.insert(trace.end(), y.begin(), y.end());
    }
    return true;
  }

 private:
  int n_;
};

struct Outcome {
  IntegratorSummary sum;
  std::vector<double> y, trace;
};

Outcome run(Integrator& integ, OdeSystem& sys, double t0, double t1, std::vector<double> y) {
  Recorder rec(sys.size());
  Outcome o;
  o.sum = integ.integrate(sys, t0, t1, y.data(), &rec);
  o.y = y;
  o.trace = rec.trace;
  return o;
}

// Bit-for-bit: == on every double (none is NaN here), and the counters.
void check_identical(const Outcome& a, const Outcome& b) {
  CHECK(a.sum.status == b.sum.status);
  CHECK(a.sum.event_index == b.sum.event_index);
  CHECK(a.sum.message == b.sum.message);
  CHECK(a.sum.t == b.sum.t);
  CHECK(a.sum.steps == b.sum.steps);
  CHECK(a.sum.rejected_steps == b.sum.rejected_steps);
  CHECK(a.sum.rhs_evals == b.sum.rhs_evals);
  CHECK(a.y == b.y);
  REQUIRE(a.trace.size() == b.trace.size());
  CHECK(a.trace == b.trace);
}

// The oscillator with a right-hand side that is NaN at t > t_bad, or from the (n_good + 1)-th
// evaluation on (a model whose state went bad for good).
class NanRhs : public OdeSystem {
 public:
  NanRhs(double t_bad, long n_good) : t_bad_(t_bad), n_good_(n_good) {}
  int size() const override { return 2; }
  void calc_rhs(double t, const double* y, double* dy) override {
    const bool bad = t > t_bad_ || ++evals_ > n_good_;
    dy[0] = bad ? std::nan("") : y[1];
    dy[1] = -y[0];
  }

 private:
  double t_bad_;
  long n_good_, evals_ = 0;
};

class Throws : public OdeSystem {
 public:
  int size() const override { return 2; }
  void calc_rhs(double t, const double* y, double* dy) override {
    if (t > 0.5) throw std::runtime_error("model left its domain");
    dy[0] = y[1];
    dy[1] = -y[0];
  }
};

}  // namespace

TEST_CASE("one CvodeIntegrator reused over different systems matches fresh integrators bit for bit",
          "[integrators][cvode]") {
  IntegratorOptions base;
  IntegratorOptions loose = base;
  loose.rtol = 1e-6;
  loose.atol = 1e-9;
  loose.max_step = 0.05;
  loose.initial_step = 1e-3;
  loose.max_steps = 5000;

  // Sizes 2 and 3, 0 to 2 events, directions that change between calls of the same size
  // (CVODE keeps root directions when CVodeRootInit is called with an unchanged count), and
  // options that set and then clear the initial and maximum step.
  TestSystem osc_fall(2, 0.0, {{0, -1}});
  TestSystem osc_none(2, 0.0, {});
  TestSystem damped_two(3, 0.1, {{0, +1}, {1, 0}});
  TestSystem damped_fall(3, 0.1, {{0, -1}});
  TestSystem damped_rise(3, 0.1, {{0, +1}});
  struct Call {
    OdeSystem* sys;
    IntegratorOptions opts;
    double t0, t1;
    std::vector<double> y0;
  };
  const std::vector<Call> calls = {
      {&osc_fall, base, 0.0, 10.0, {1.0, 0.0}},
      {&damped_two, base, 1.0, 20.0, {0.5, 0.8, 0.0}},
      {&damped_fall, loose, 2.0, 20.0, {0.5, 0.8, 0.1}},
      {&damped_rise, base, 2.0, 20.0, {0.5, 0.8, 0.1}},
      {&osc_none, loose, 0.0, 3.0, {0.0, 1.0}},
      {&osc_none, base, 0.0, 3.0, {0.0, 1.0}},
      {&damped_two, base, 1.0, 20.0, {0.5, 0.8, 0.0}},
  };
  CvodeIntegrator reused(base);
  std::vector<Outcome> first;
  for (std::size_t i = 0; i < calls.size(); ++i) {
    const Call& c = calls[i];
    INFO("call " << i);
    reused.set_options(c.opts);
    const Outcome a = run(reused, *c.sys, c.t0, c.t1, c.y0);
    CvodeIntegrator fresh(c.opts);
    const Outcome b = run(fresh, *c.sys, c.t0, c.t1, c.y0);
    CHECK(a.sum.status != IntegratorStatus::failure);
    CHECK(a.sum.steps > 10);
    check_identical(a, b);
    first.push_back(a);
  }
  // The event each call must stop at (the directions are honoured on reuse).
  CHECK(first[0].sum.status == IntegratorStatus::event);
  CHECK(first[2].sum.status == IntegratorStatus::event);
  CHECK(first[3].sum.status == IntegratorStatus::event);
  CHECK(first[2].y[1] < 0.0);  // falling zero of y0
  CHECK(first[3].y[1] > 0.0);  // rising zero of y0
  CHECK(first[4].sum.status == IntegratorStatus::reached_end);
  // Counters are per call: the repeated last call counts what the second one did.
  check_identical(first[1], first[6]);
}

TEST_CASE("CVODE on the harmonic oscillator: accuracy follows rtol", "[integrators][cvode]") {
  // y'' = -y, y(0) = 1, y'(0) = 0: y = cos t, y' = -sin t; at pi/2: (0, -1).
  // The bound: CVODE accepts a step when the weighted RMS norm of its local error estimate is
  // <= 1 with weights 1 / (rtol |y_i| + atol); with |y_i| <= 1 and n = 2 that makes the local
  // error <= sqrt(2) (rtol + atol) in the Euclidean norm. The flow is a rotation, which carries
  // each local error to pi/2 with its norm unchanged, so the global error is at most the sum,
  // steps * sqrt(2) (rtol + atol). (Measured: 13.5, 7.9 and 2.3 rtol with 34, 49 and 77 steps,
  // well inside.) The bound grows with the step count, so the scaling check below is what
  // catches tolerances that do not reach CVODE.
  TestSystem osc(2, 0.0, {});
  CvodeIntegrator cv(IntegratorOptions{});
  std::vector<double> errs;
  for (double rtol : {1e-6, 1e-8, 1e-10}) {
    IntegratorOptions o;
    o.rtol = rtol;
    o.atol = 1e-3 * rtol;
    cv.set_options(o);
    double y[2] = {1.0, 0.0};
    const IntegratorSummary s = cv.integrate(osc, 0.0, kPi / 2, y, nullptr);
    REQUIRE(s.status == IntegratorStatus::reached_end);
    CHECK(s.t == kPi / 2);
    const double err = std::max(std::abs(y[0] - std::cos(kPi / 2)), std::abs(y[1] + std::sin(kPi / 2)));
    INFO("rtol " << rtol << " error " << err << " steps " << s.steps);
    CHECK(err < s.steps * std::sqrt(2.0) * (o.rtol + o.atol));
    errs.push_back(err);
  }
  // Tightening rtol by 100 must shrink the error by well over 10.
  CHECK(errs[1] < 0.1 * errs[0]);
  CHECK(errs[2] < 0.1 * errs[1]);
}

TEST_CASE("events: y crossing zero located against the analytic time", "[integrators][events]") {
  // y = cos t crosses zero falling at pi/2 and rising at 3 pi/2 (y' = -sin t = -+1 there).
  // The event time has two errors: locating the root of the computed solution (CVODE: about
  // 100 eps (|t| + |h|); DOPRI5: event_time_tol on its dense output) and the error of the
  // computed solution itself, which shifts its root by |error in y| / |y'| = |error in y|.
  // The first is checked on the returned state (|g| <= event_time_tol |y'| + roundoff), the
  // second against the analytic time with the global error bound of the accuracy test above,
  // steps * sqrt(2) (rtol + atol) (DOPRI5 controls the same per-step error measure), plus
  // event_time_tol.
  IntegratorOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-13;
  for (int which = 0; which < 2; ++which) {
    CvodeIntegrator cv(o);
    DormandPrince54 dp(o);
    Integrator& integ = which == 0 ? static_cast<Integrator&>(cv) : dp;
    for (int dir : {-1, +1}) {
      INFO((which == 0 ? "CVODE" : "DOPRI5") << ", direction " << dir);
      TestSystem osc(2, 0.0, {{0, dir}});
      double y[2] = {1.0, 0.0};
      const IntegratorSummary s = integ.integrate(osc, 0.0, 10.0, y, nullptr);
      REQUIRE(s.status == IntegratorStatus::event);
      CHECK(s.event_index == 0);
      const double t_exact = dir < 0 ? kPi / 2 : 3 * kPi / 2;
      INFO("steps " << s.steps << ", event time error " << s.t - t_exact);
      CHECK(std::abs(s.t - t_exact) < s.steps * std::sqrt(2.0) * (o.rtol + o.atol) + o.event_time_tol);
      CHECK(std::abs(y[0]) <= o.event_time_tol + 1e-14);
      CHECK(y[1] * dir > 0.0);
    }
  }
}

TEST_CASE("invalid options end with failure naming the field", "[integrators][options]") {
  TestSystem osc(2, 0.0, {});
  for (double rtol : {0.0, -1e-6}) {
    IntegratorOptions bad;
    bad.rtol = rtol;
    CvodeIntegrator cv(bad);
    DormandPrince54 dp(bad);
    for (Integrator* integ : {static_cast<Integrator*>(&cv), static_cast<Integrator*>(&dp)}) {
      double y[2] = {1.0, 0.0};
      const IntegratorSummary s = integ->integrate(osc, 0.0, 1.0, y, nullptr);
      CHECK(s.status == IntegratorStatus::failure);
      CHECK_THAT(s.message, Contains("rtol"));
      CHECK(s.steps == 0);
      CHECK(y[0] == 1.0);  // untouched
      CHECK(y[1] == 0.0);
    }
    // Valid options again: the same objects integrate.
    cv.set_options(IntegratorOptions{});
    double y[2] = {1.0, 0.0};
    CHECK(cv.integrate(osc, 0.0, 1.0, y, nullptr).status == IntegratorStatus::reached_end);
  }
}

TEST_CASE("max_steps bounds the accepted steps of a call, for both integrators", "[integrators][options]") {
  TestSystem osc(2, 0.0, {});
  IntegratorOptions o;
  o.max_steps = 50;
  CvodeIntegrator cv(o);
  DormandPrince54 dp(o);
  for (Integrator* integ : {static_cast<Integrator*>(&cv), static_cast<Integrator*>(&dp)}) {
    double y[2] = {1.0, 0.0};
    const IntegratorSummary s = integ->integrate(osc, 0.0, 1000.0, y, nullptr);
    CHECK(s.status == IntegratorStatus::step_limit);
    CHECK(s.steps == 50);
    CHECK(s.t > 0.0);
    CHECK(s.t < 1000.0);
  }
}

TEST_CASE("a NaN right-hand side ends CVODE with failure and its flag", "[integrators][cvode]") {
  TestSystem osc(2, 0.0, {});
  CvodeIntegrator cv(IntegratorOptions{});
  SECTION("NaN from the start") {
    NanRhs sys(-1.0, 1'000'000);
    double y[2] = {1.0, 0.0};
    const IntegratorSummary s = cv.integrate(sys, 0.0, 2.0, y, nullptr);
    CHECK(s.status == IntegratorStatus::failure);
    CHECK_THAT(s.message, Contains("CV_FIRST_RHSFUNC_ERR"));
  }
  SECTION("NaN from the 100th evaluation on: CVODE cuts the step until it gives up") {
    NanRhs sys(1e300, 100);
    double y[2] = {1.0, 0.0};
    const IntegratorSummary s = cv.integrate(sys, 0.0, 10.0, y, nullptr);
    CHECK(s.status == IntegratorStatus::failure);
    // The fixed-point corrector turns a failed evaluation into a convergence failure; after
    // CVODE's 10 retries of the step it returns CV_CONV_FAILURE (CV_REPTD_RHSFUNC_ERR when the
    // failed evaluation is the first of a step).
    CHECK_THAT(s.message, Matches("CVODE flag -[0-9]+ \\((CV_CONV_FAILURE|CV_REPTD_RHSFUNC_ERR)\\) at t = .*"));
    CHECK(s.t > 0.0);
    CHECK(s.t < 10.0);
    CHECK(std::isfinite(y[0]));
    CHECK(std::isfinite(y[1]));
  }
  SECTION("NaN beyond t = 1: the steps shrink onto t = 1 until t + h == t") {
    // Every step that ends at or before 1 succeeds, so CVODE never reports a failure of its own;
    // without the no-progress check this spun until max_steps (or forever before max_steps was
    // enforced).
    NanRhs sys(1.0, 1'000'000);
    double y[2] = {1.0, 0.0};
    const IntegratorSummary s = cv.integrate(sys, 0.0, 2.0, y, nullptr);
    CHECK(s.status == IntegratorStatus::failure);
    CHECK_THAT(s.message, Contains("no progress"));
    CHECK(s.t <= 1.0);
    CHECK(s.t > 1.0 - 1e-12);
    CHECK(s.steps < 1000);
    CHECK(std::abs(y[0] - std::cos(1.0)) < 1e-6);
  }
  SECTION("an exception of the system reaches the caller") {
    Throws sys;
    double y[2] = {1.0, 0.0};
    CHECK_THROWS_WITH(cv.integrate(sys, 0.0, 2.0, y, nullptr), "model left its domain");
  }
  // After the failure the same object integrates as a fresh one.
  CvodeIntegrator fresh(IntegratorOptions{});
  check_identical(run(cv, osc, 0.0, 3.0, {1.0, 0.0}), run(fresh, osc, 0.0, 3.0, {1.0, 0.0}));
}

TEST_CASE("SUNDIALS flag checks name the solver, the function and the flag", "[integrators][sundials]") {
  using namespace truss::integrators;
  IntegratorSummary sum;
  sum.status = IntegratorStatus::reached_end;
  CHECK(sunflags::check_flag(0, "CVODE", CVodeGetReturnFlagName, "CVode", sum));
  CHECK(sunflags::check_flag(2, "CVODE", CVodeGetReturnFlagName, "CVode", sum));  // CV_ROOT_RETURN: not a failure
  CHECK(sum.status == IntegratorStatus::reached_end);  // untouched
  CHECK(sum.message.empty());
  // Flag -1 is CV_TOO_MUCH_WORK and IDA_TOO_MUCH_WORK (cvode.h, ida.h of SUNDIALS 6).
  CHECK_FALSE(sunflags::check_flag(-1, "CVODE", CVodeGetReturnFlagName, "CVode", sum));
  CHECK(sum.status == IntegratorStatus::failure);
  CHECK(sum.message == "CVODE: CVode failed with flag -1 (CV_TOO_MUCH_WORK)");
  IntegratorSummary s2;
  CHECK_FALSE(sunflags::check_flag(-1, "IDA", IDAGetReturnFlagName, "IDASolve", s2));
  CHECK(s2.message == "IDA: IDASolve failed with flag -1 (IDA_TOO_MUCH_WORK)");
  IntegratorSummary s3;
  CHECK_FALSE(sunflags::check_null(nullptr, "IDA", "N_VNew_Serial", s3));
  CHECK(s3.message == "IDA: N_VNew_Serial returned NULL");
  IntegratorSummary s4;
  CHECK(sunflags::check_sundials(0, "CVODE", "SUNContext_Create", s4));
  CHECK_FALSE(sunflags::check_sundials(3, "CVODE", "SUNContext_Create", s4));
  CHECK(s4.message == "CVODE: SUNContext_Create failed with flag 3");
}

namespace {
// n decoupled stiff equations y_i' = -1000 (y_i - cos t) whose right-hand side takes 0.5 ms: a
// Newton-matrix set-up (n right-hand sides for the Jacobian) costs n x 0.5 ms, far more than a step.
class SlowStiffSystem : public OdeSystem {
 public:
  explicit SlowStiffSystem(int n) : n_(n) {}
  int size() const override { return n_; }
  void calc_rhs(double t, const double* y, double* dy) override {
    std::this_thread::sleep_for(std::chrono::microseconds(500));
    for (int i = 0; i < n_; ++i) dy[i] = -1000.0 * (y[i] - std::cos(t + i));
  }
 private:
  int n_;
};
class DeadlineObserver : public StepObserver {
 public:
  explicit DeadlineObserver(std::chrono::steady_clock::time_point d) : d_(d) {}
  bool on_step(const DenseOutput&) override { return std::chrono::steady_clock::now() <= d_; }
  std::chrono::steady_clock::time_point deadline() const override { return d_; }
 private:
  std::chrono::steady_clock::time_point d_;
};
}  // namespace

TEST_CASE("CVODE BDF keeps a wall-clock deadline inside a Newton-matrix set-up", "[integrators][cvode]") {
  // 300 equations: a set-up takes 300 x 0.5 ms = 0.15 s, steps a few ms. Set-ups come every few
  // steps, so if only the observer read the clock (after a step) the run would end up to one
  // set-up (0.15 s) past the deadline; the right-hand side reads it every few evaluations, so the
  // run ends within a few of them (a few ms).
  SlowStiffSystem sys(300);
  IntegratorOptions o;
  o.rtol = 1e-6;
  o.atol = 1e-8;
  CvodeIntegrator cvode(o);
  std::vector<double> y(300, 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  const double budget_s = 0.6;
  DeadlineObserver obs(t0 + std::chrono::milliseconds(600));
  const IntegratorSummary s = cvode.integrate(sys, 0.0, 1e3, y.data(), &obs);
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO(s.to_string() << ", took " << took_s << " s");
  CHECK((s.status == IntegratorStatus::deadline || s.status == IntegratorStatus::stopped_by_observer));
  CHECK(took_s < budget_s + 0.05);  // a step (a few right-hand sides) past it at most, not a 0.15 s set-up
}

namespace {
// n linear equations y_i' = -1e3 y_i + 0.1 sum_j y_j + 1, coupled densely: cheap right-hand sides,
// so a Newton-matrix set-up is all LU (2n^3/3 operations: seconds at n = 3,000). From y = 1 the
// difference quotients of the coupling (0.1 x sqrt(eps)) stand well above the rounding of f, so
// the Newton matrix is full.
class DenseCoupledSystem : public OdeSystem {
 public:
  explicit DenseCoupledSystem(int n) : n_(n) {}
  int size() const override { return n_; }
  void calc_rhs(double, const double* y, double* dy) override {
    double sum = 0.0;
    for (int i = 0; i < n_; ++i) sum += y[i];
    for (int i = 0; i < n_; ++i) dy[i] = -1e3 * y[i] + 0.1 * sum + 1.0;
  }
 private:
  int n_;
};
}  // namespace

TEST_CASE("CVODE BDF stops inside its first Newton-matrix LU at a wall-clock deadline", "[integrators][cvode]") {
  // n = 3,000: the first LU alone (2n^3/3 = 1.8e10 operations in SUNDIALS' column-wise dense LU)
  // takes several seconds, the Jacobian before it (n cheap right-hand sides) a small part of the
  // 0.4 s to the deadline. The promise of a run's cap: it ends within 0.5 s of the deadline (the
  // cap plus 5 % or 0.5 s), with the deadline's status.
  DenseCoupledSystem sys(3000);
  IntegratorOptions o;
  o.rtol = 1e-6;
  o.atol = 1e-8;
  CvodeIntegrator cvode(o);
  std::vector<double> y(3000, 1.0);
  const auto t0 = std::chrono::steady_clock::now();
  DeadlineObserver obs(t0 + std::chrono::milliseconds(400));
  const IntegratorSummary s = cvode.integrate(sys, 0.0, 1e3, y.data(), &obs);
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO(s.to_string() << ", took " << took_s << " s");
  CHECK(s.status == IntegratorStatus::deadline);
  CHECK(took_s < 0.4 + 0.5);
  // The same solver object goes on after a deadline (new SUNDIALS objects): a small system to its end.
  DenseCoupledSystem small(3);
  std::vector<double> y3(3, 0.0);
  const IntegratorSummary s3 = cvode.integrate(small, 0.0, 1.0, y3.data(), nullptr);
  CHECK(s3.status == IntegratorStatus::reached_end);
  // y_i' = -1e3 y_i + 0.1 (y_1 + y_2 + y_3) + 1 at rest: y_i = 1 / (1e3 - 0.3).
  CHECK(y3[0] == Approx(1.0 / (1e3 - 0.3)).epsilon(1e-5));
}
