#include "integrators/dopri54.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "numerics/illinois.hpp"

namespace truss::integrators {

const char* to_string(IntegratorStatus s) {
  switch (s) {
    case IntegratorStatus::reached_end: return "reached end";
    case IntegratorStatus::event: return "event";
    case IntegratorStatus::step_limit: return "step limit";
    case IntegratorStatus::stopped_by_observer: return "stopped by observer";
    case IntegratorStatus::failure: return "failure";
    case IntegratorStatus::stiff: return "stiff";
    case IntegratorStatus::deadline: return "wall-clock deadline";
  }
  return "?";
}

std::string IntegratorSummary::to_string() const {
  return fmt::format("{} at t = {:.9g} s: {} steps ({} rejected), {} rhs evaluations{}{}",
                     integrators::to_string(status), t, steps, rejected_steps, rhs_evals,
                     message.empty() ? "" : "; ", message);
}

std::string IntegratorOptions::validate() const {
  if (!(rtol > 0.0 && rtol < 1.0)) return fmt::format("rtol: must lie in (0, 1), got {}", rtol);
  if (!(atol > 0.0)) return fmt::format("atol: must be positive, got {}", atol);
  if (!(initial_step >= 0.0)) return "initial_step: must not be negative";
  if (!(max_step > 0.0)) return "max_step: must be positive";
  if (!(fixed_step >= 0.0)) return "fixed_step: must not be negative";
  if (max_steps <= 0) return "max_steps: must be positive";
  if (!(event_time_tol > 0.0)) return "event_time_tol: must be positive";
  return {};
}

namespace {

// Butcher tableau of DOPRI5.
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784,
                 a76 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;
constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                 d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                 d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

class Dopri5Dense : public DenseOutput {
 public:
  const std::vector<double>* rc = nullptr;  // 5 coefficient vectors
  const double* y_end = nullptr;             // the step's end state: returned as is at t0 + h
  double t0 = 0, h = 0;
  int n = 0;
  void calc_state(double t, double* y) const override {
    if (y_end && t == t0 + h) {
      std::copy(y_end, y_end + n, y);
      return;
    }
    const double th = (t - t0) / h, th1 = 1.0 - th;
    for (int i = 0; i < n; ++i)
      y[i] = rc[0][i] + th * (rc[1][i] + th1 * (rc[2][i] + th * (rc[3][i] + th1 * rc[4][i])));
  }
};

bool crosses(double g0, double g1, int dir) {
  if (dir >= 0 && g0 < 0.0 && g1 >= 0.0) return true;
  if (dir <= 0 && g0 > 0.0 && g1 <= 0.0) return true;
  return false;
}

}  // namespace

// Initial step: Hairer's heuristic with one explicit Euler probe (k_[0] holds f(t, y)).
double DormandPrince54::calc_initial_step(OdeSystem& sys, double t, const double* y, double span,
                                          IntegratorSummary& sum) {
  const int n = sys.size();
  double h;
  if (opts_.fixed_step > 0.0) {
    h = opts_.fixed_step;
  } else if (opts_.initial_step > 0.0) {
    h = opts_.initial_step;
  } else if (h_last_ > 0.0) {
    h = h_last_;
  } else {
    double d0 = 0, d1n = 0;
    for (int i = 0; i < n; ++i) {
      const double sc = calc_scale(y[i], y[i]);
      d0 += (y[i] / sc) * (y[i] / sc);
      d1n += (k_[0][i] / sc) * (k_[0][i] / sc);
    }
    d0 = std::sqrt(d0 / n); d1n = std::sqrt(d1n / n);
    double h0 = (d0 < 1e-5 || d1n < 1e-5) ? 1e-6 : 0.01 * d0 / d1n;
    h0 = std::min(h0, span);
    for (int i = 0; i < n; ++i) ytmp_[i] = y[i] + h0 * k_[0][i];
    sys.calc_rhs(t + h0, ytmp_.data(), k_[1].data());
    ++sum.rhs_evals;
    double d2 = 0;
    for (int i = 0; i < n; ++i) {
      const double sc = calc_scale(y[i], y[i]);
      const double v = (k_[1][i] - k_[0][i]) / sc;
      d2 += v * v;
    }
    d2 = std::sqrt(d2 / n) / h0;
    const double dm = std::max(d1n, d2);
    const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 5.0);
    h = std::min(100.0 * h0, h1);
  }
  return std::min({h, opts_.max_step, span});
}

// One Dormand-Prince step of size h from (t, y) into ynew_; returns the scaled RMS error
// estimate (NaN if the state is not finite).
double DormandPrince54::attempt_step(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum) {
  const int n = sys.size();
  auto& k1 = k_[0]; auto& k2 = k_[1]; auto& k3 = k_[2]; auto& k4 = k_[3];
  auto& k5 = k_[4]; auto& k6 = k_[5]; auto& k7 = k_[6];
  for (int i = 0; i < n; ++i) ytmp_[i] = y[i] + h * a21 * k1[i];
  sys.calc_rhs(t + c2 * h, ytmp_.data(), k2.data());
  for (int i = 0; i < n; ++i) ytmp_[i] = y[i] + h * (a31 * k1[i] + a32 * k2[i]);
  sys.calc_rhs(t + c3 * h, ytmp_.data(), k3.data());
  for (int i = 0; i < n; ++i) ytmp_[i] = y[i] + h * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
  sys.calc_rhs(t + c4 * h, ytmp_.data(), k4.data());
  for (int i = 0; i < n; ++i)
    ytmp_[i] = y[i] + h * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
  sys.calc_rhs(t + c5 * h, ytmp_.data(), k5.data());
  for (int i = 0; i < n; ++i)
    ytmp_[i] = y[i] + h * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
  sys.calc_rhs(t + h, ytmp_.data(), k6.data());
  for (int i = 0; i < n; ++i)
    ynew_[i] = y[i] + h * (a71 * k1[i] + a73 * k3[i] + a74 * k4[i] + a75 * k5[i] + a76 * k6[i]);
  sys.calc_rhs(t + h, ynew_.data(), k7.data());
  sum.rhs_evals += 6;
  double err = 0.0;
  bool finite = true;
  for (int i = 0; i < n; ++i) {
    const double e = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
    const double v = e / calc_scale(y[i], ynew_[i]);
    err += v * v;
    finite = finite && std::isfinite(ynew_[i]);
  }
  err = std::sqrt(err / n);
  return finite ? err : std::numeric_limits<double>::quiet_NaN();
}

// Dense output coefficients of the accepted step on [t, t + h].
void DormandPrince54::fill_dense(int n, double h, const double* y) {
  const auto& k1 = k_[0]; const auto& k3 = k_[2]; const auto& k4 = k_[3];
  const auto& k5 = k_[4]; const auto& k6 = k_[5]; const auto& k7 = k_[6];
  for (int i = 0; i < n; ++i) {
    const double ydiff = ynew_[i] - y[i];
    const double bspl = h * k1[i] - ydiff;
    rc_[0][i] = y[i];
    rc_[1][i] = ydiff;
    rc_[2][i] = bspl;
    rc_[3][i] = ydiff - h * k7[i] - bspl;
    rc_[4][i] = h * (d1 * k1[i] + d3 * k3[i] + d4 * k4[i] + d5 * k5[i] + d6 * k6[i] + d7 * k7[i]);
  }
}

// Events: the earliest sign change in the allowed direction over [t, t_new], refined by the
// Illinois method on the dense output. Returns the event index (or -1) and its time in t_ev.
int DormandPrince54::find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev) {
  const int ne = sys.num_events();
  int ev = -1;
  t_ev = t_new;
  if (ne == 0) return ev;
  sys.calc_events(t_new, ynew_.data(), g1_.data());
  for (int e = 0; e < ne; ++e) {
    if (!crosses(g0_[e], g1_[e], sys.event_direction(e))) continue;
    // Below a few ulps of t the bracket cannot shrink (t > 512 s: ulp > 1e-13 s); stop there
    // instead of spending the 200 iterations.
    const double tol = std::max(opts_.event_time_tol, 4.0 * std::numeric_limits<double>::epsilon() * std::abs(t_new));
    const double root = numerics::find_crossing_illinois([&](double tc) {  // on the side where the event has happened
      dense.calc_state(tc, yev_.data());
      sys.calc_events(tc, yev_.data(), gt_.data());
      return gt_[e];
    }, t, g0_[e], t_new, g1_[e], tol);
    if (root < t_ev || ev < 0) { t_ev = root; ev = e; }
  }
  return ev;
}

bool StiffnessTest::update(double h, const std::vector<double>& k7, const std::vector<double>& k6,
                           const std::vector<double>& y7, const std::vector<double>& y6) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < k7.size(); ++i) {
    num += (k7[i] - k6[i]) * (k7[i] - k6[i]);
    den += (y7[i] - y6[i]) * (y7[i] - y6[i]);
  }
  if (!(den > 0.0)) return false;
  if (h * std::sqrt(num / den) > boundary) {
    non_stiff = 0;
    return ++stiff_steps >= 15;
  }
  if (++non_stiff >= 6) stiff_steps = 0;
  return false;
}

IntegratorSummary DormandPrince54::integrate(OdeSystem& sys, double t0, double t_end, double* y,
                                             StepObserver* observer) {
  IntegratorSummary sum;
  if (const std::string bad = opts_.validate(); !bad.empty()) {
    sum.t = t0;
    sum.status = IntegratorStatus::failure;
    sum.message = "invalid integrator options: " + bad;
    return sum;
  }
  const int n = sys.size();
  for (auto& k : k_) k.assign(n, 0.0);
  for (auto& r : rc_) r.assign(n, 0.0);
  ytmp_.assign(n, 0.0); ynew_.assign(n, 0.0); err_.assign(n, 0.0);
  const int ne = sys.num_events();
  g0_.assign(ne, 0.0); g1_.assign(ne, 0.0); gt_.assign(ne, 0.0); yev_.assign(n, 0.0);

  const double span = t_end - t0;
  double t = t0;
  sum.t = t;
  if (!(span > 0.0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  const bool fixed = opts_.fixed_step > 0.0;
  sys.calc_rhs(t, y, k_[0].data());
  ++sum.rhs_evals;
  if (ne > 0) sys.calc_events(t, y, g0_.data());
  double h = calc_initial_step(sys, t, y, span, sum);

  double err_prev = 1e-4;  // PI controller memory (Gustafsson)
  bool last_rejected = false;
  StiffnessTest stiffness;
  Dopri5Dense dense;
  dense.rc = rc_;
  dense.y_end = ynew_.data();
  dense.n = n;
  auto finish = [&](IntegratorStatus st, double t_at, std::string msg = {}) {
    sum.status = st;
    sum.t = t_at;
    sum.message = std::move(msg);
    return sum;
  };
  while (true) {
    if (sum.steps >= opts_.max_steps)
      return finish(IntegratorStatus::step_limit, t, fmt::format("step limit of {} reached", opts_.max_steps));
    bool last = false;
    if (t + h >= t_end || (t_end - (t + h)) < 1e-12 * std::abs(t_end)) { h = t_end - t; last = true; }
    const double err = attempt_step(sys, t, h, y, sum);
    if (!std::isfinite(err)) {
      if (fixed || h < 1e-14 * std::max(1.0, std::abs(t)))
        return finish(IntegratorStatus::failure, t, fmt::format("non-finite state at t = {:.9g} s", t));
      h *= 0.25; last_rejected = true; ++sum.rejected_steps;
      continue;
    }
    if (!fixed && err > 1.0) {
      const double fac = std::max(0.2, 0.9 * std::pow(err, -0.2));
      h *= fac;
      last_rejected = true;
      ++sum.rejected_steps;
      if (h < 1e-14 * std::max(1.0, std::abs(t)))
        return finish(IntegratorStatus::failure, t, fmt::format("step size underflow at t = {:.9g} s", t));
      continue;
    }
    fill_dense(n, h, y);
    dense.t0 = t; dense.h = h; dense.t_begin = t; dense.t_end = t + h;
    ++sum.steps;
    const double t_new = t + h;
    double t_ev;
    const int ev = find_event(sys, t, t_new, dense, t_ev);
    if (ev >= 0) {
      dense.t_end = t_ev;
      dense.calc_state(t_ev, y);
      if (observer) observer->on_step(dense);
      sum.event_index = ev;
      h_last_ = h;
      return finish(IntegratorStatus::event, t_ev);
    }
    if (observer && !observer->on_step(dense)) {
      std::copy(ynew_.begin(), ynew_.end(), y);
      return finish(IntegratorStatus::stopped_by_observer, t_new);
    }
    // k6 = f(t + h, ytmp_) (stage 6) and k7 = f(t + h, ynew_): h |lambda| ~ h |k7 - k6| / |ynew - ytmp|.
    const bool stiff = opts_.stop_when_stiff && !fixed && stiffness.update(h, k_[6], k_[5], ynew_, ytmp_);
    std::copy(ynew_.begin(), ynew_.end(), y);
    std::swap(k_[0], k_[6]);  // FSAL
    if (ne > 0) std::swap(g0_, g1_);
    t = t_new;
    if (last) return finish(IntegratorStatus::reached_end, t);
    if (stiff)
      return finish(IntegratorStatus::stiff, t, fmt::format("stiff at t = {:.9g} s (h |lambda| > 3.25 on 15 steps)", t));
    if (!fixed) {
      // PI step control (Hairer's DOPRI5: beta = 0.04), no growth right after a rejection.
      const double e = std::max(err, 1e-10);
      double fac = 0.9 * std::pow(e, -0.2 + 0.04 * 0.75) * std::pow(err_prev, 0.04);
      fac = std::clamp(fac, 0.2, last_rejected ? 1.0 : 10.0);
      err_prev = std::max(err, 1e-4);
      h = std::min(h * fac, opts_.max_step);
      h_last_ = h;
      last_rejected = false;
    }
  }
}

}  // namespace truss::integrators
