// DOP853 (integrators/dop853.hpp) against closed-form solutions: its order 8 at a fixed step on
// a nonlinear system, the order of its dense output, accuracy that follows rtol, event times (its
// stiffness test: test_robustness.cpp, beside DOPRI5's).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "integrators/dop853.hpp"

using namespace truss::integrators;

namespace {

constexpr double kPi = std::numbers::pi;

// The circular Kepler orbit: x'' = -x / |x|^3 with x(0) = (1, 0), x'(0) = (0, 1) has the solution
// x = (cos t, sin t), a nonlinear system (its Jacobian changes along the orbit) with a closed form.
// Event 0: x_1 = sin t crossing zero in the given direction.
class Orbit : public OdeSystem {
 public:
  explicit Orbit(int direction = 0, bool event = false) : dir_(direction), event_(event) {}
  int size() const override { return 4; }
  void calc_rhs(double, const double* y, double* dy) override {
    const double r2 = y[0] * y[0] + y[1] * y[1], r3 = r2 * std::sqrt(r2);
    dy[0] = y[2];
    dy[1] = y[3];
    dy[2] = -y[0] / r3;
    dy[3] = -y[1] / r3;
  }
  int num_events() const override { return event_ ? 1 : 0; }
  void calc_events(double, const double* y, double* g) override { g[0] = y[1]; }
  int event_direction(int) const override { return dir_; }
  static void exact(double t, double* y) {
    y[0] = std::cos(t); y[1] = std::sin(t); y[2] = -std::sin(t); y[3] = std::cos(t);
  }

 private:
  int dir_;
  bool event_;
};

double max_error(double t, const double* y) {
  double e[4];
  Orbit::exact(t, e);
  double m = 0.0;
  for (int i = 0; i < 4; ++i) m = std::max(m, std::abs(y[i] - e[i]));
  return m;
}

// Largest error of the dense output at the middle of every step.
class MidStepError : public StepObserver {
 public:
  double worst = 0.0;
  bool on_step(const DenseOutput& d) override {
    const double t = 0.5 * (d.t_begin + d.t_end);
    double y[4];
    d.calc_state(t, y);
    worst = std::max(worst, max_error(t, y));
    return true;
  }
};

}  // namespace

TEST_CASE("DOP853 at a fixed step: global error of order 8, dense output of order 7", "[integrators][dop853]") {
  // Halving the step of a method of order p divides the global error by 2^p = 256 once the
  // leading term dominates; the dense output of order 7 has a local error O(h^8) on top of the
  // global O(h^8), so its error also falls by about 2^8. The steps chosen (0.5 and 0.25 on
  // [0, 4]) keep the errors far above roundoff (about 1e-9 and 4e-12) and the observed orders
  // within 7.5 .. 8.5 (a coefficient of the wrong value drops the order to 4 or less).
  std::vector<double> end_err, mid_err;
  for (double h : {0.5, 0.25}) {
    IntegratorOptions o;
    o.fixed_step = h;
    Dop853 dop(o);
    Orbit orbit;
    MidStepError mid;
    double y[4] = {1.0, 0.0, 0.0, 1.0};
    const IntegratorSummary s = dop.integrate(orbit, 0.0, 4.0, y, &mid);
    REQUIRE(s.status == IntegratorStatus::reached_end);
    CHECK(s.steps == static_cast<long>(std::lround(4.0 / h)));
    end_err.push_back(max_error(4.0, y));
    mid_err.push_back(mid.worst);
  }
  const double p_end = std::log2(end_err[0] / end_err[1]), p_mid = std::log2(mid_err[0] / mid_err[1]);
  INFO("errors at t = 4: " << end_err[0] << ", " << end_err[1] << " (order " << p_end << "); mid-step: " << mid_err[0]
                           << ", " << mid_err[1] << " (order " << p_mid << ")");
  CHECK(p_end > 7.5);
  CHECK(p_end < 8.5);
  CHECK(p_mid > 7.0);
  CHECK(end_err[1] > 1e-13);  // still above roundoff: the order measured is the method's
}

TEST_CASE("DOP853 adaptive: the error follows rtol; events located against the analytic time", "[integrators][dop853]") {
  // As the CVODE and DOPRI5 tests (test_integrators.cpp): a step is accepted when its scaled error
  // (weights 1 / (atol + rtol |y_i|), RMS over the 4 components) is <= 1, so each local error is
  // <= 2 (rtol + atol) in the max norm (|y_i| <= 1); the orbit's flow is a rotation in the
  // position and velocity pairs, which carries each local error forward without growth at first
  // order (the radial error's secular drift stays far below the bound over 2 pi), so the global
  // error is at most steps * 2 (rtol + atol).
  std::vector<double> errs;
  for (double rtol : {1e-6, 1e-9, 1e-12}) {
    IntegratorOptions o;
    o.rtol = rtol;
    o.atol = 1e-3 * rtol;
    Dop853 dop(o);
    Orbit orbit;
    double y[4] = {1.0, 0.0, 0.0, 1.0};
    const IntegratorSummary s = dop.integrate(orbit, 0.0, 2.0 * kPi, y, nullptr);
    REQUIRE(s.status == IntegratorStatus::reached_end);
    const double err = max_error(2.0 * kPi, y);
    INFO("rtol " << rtol << " error " << err << " steps " << s.steps);
    CHECK(err < s.steps * 2.0 * (o.rtol + o.atol));
    errs.push_back(err);
  }
  CHECK(errs[1] < 0.01 * errs[0]);  // a factor 1000 in rtol: well over 100 in the error
  CHECK(errs[2] < 0.01 * errs[1]);
  for (int dir : {-1, +1}) {
    // sin t crosses zero falling at pi, rising at 2 pi (t > 0). Error: the solution's (bound as
    // above, divided by |d sin t / dt| = 1) plus event_time_tol.
    IntegratorOptions o;
    o.rtol = 1e-10;
    o.atol = 1e-13;
    Dop853 dop(o);
    Orbit orbit(dir, true);
    double y[4] = {1.0, 0.0, 0.0, 1.0};
    const IntegratorSummary s = dop.integrate(orbit, 0.0, 10.0, y, nullptr);
    REQUIRE(s.status == IntegratorStatus::event);
    const double t_exact = dir < 0 ? kPi : 2.0 * kPi;
    INFO("direction " << dir << ", steps " << s.steps << ", event time error " << s.t - t_exact);
    CHECK(std::abs(s.t - t_exact) < s.steps * 2.0 * (o.rtol + o.atol) + o.event_time_tol);
    CHECK(std::abs(y[1]) <= o.event_time_tol + 1e-14);  // the returned state is on the event surface
    CHECK(y[3] * dir > 0.0);
  }
}
