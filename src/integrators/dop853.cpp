#include "integrators/dop853.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "integrators/dop853_tableau.hpp"
#include "numerics/illinois.hpp"

namespace truss::integrators {

using namespace dop853;

// The step's continuous solution (dop853_tableau.hpp): the step's end is y1 itself; any other time
// first computes the three dense-output stages (once per step).
class Dop853::Dense final : public DenseOutput {
 public:
  Dop853* owner = nullptr;
  OdeSystem* sys = nullptr;
  IntegratorSummary* sum = nullptr;
  const double* y = nullptr;  // the step's start state (intact until the dense output is filled)
  double t0 = 0, h = 0;
  int n = 0;
  mutable bool ready = false;
  void fill() const {
    if (!ready) owner->fill_dense(*sys, t0, h, y, *sum);
    ready = true;
  }
  void calc_state(double t, double* out) const override {
    if (t == t0 + h) {
      std::copy(owner->ynew_.begin(), owner->ynew_.end(), out);
      return;
    }
    fill();
    const double th = (t - t0) / h, u = 1.0 - th;
    const auto& r = owner->rc_;
    const std::vector<double>& y0 = owner->ystart_;  // fill_dense keeps the start state there
    for (int i = 0; i < n; ++i)
      out[i] = y0[i] + th * (r[0][i] + u * (r[1][i] + th * (r[2][i] + u * (r[3][i] + th * (r[4][i] + u * (r[5][i] + th * r[6][i]))))));
  }
};

namespace {
bool crosses(double g0, double g1, int dir) {
  if (dir >= 0 && g0 < 0.0 && g1 >= 0.0) return true;
  if (dir <= 0 && g0 > 0.0 && g1 <= 0.0) return true;
  return false;
}
}  // namespace

// Initial step: Hairer's heuristic for an order-8 method, one explicit Euler probe (k_[0] = f(t, y)).
double Dop853::calc_initial_step(OdeSystem& sys, double t, const double* y, double span, IntegratorSummary& sum) {
  const int n = sys.size();
  double h;
  if (opts_.fixed_step > 0.0) {
    h = opts_.fixed_step;
  } else if (opts_.initial_step > 0.0) {
    h = opts_.initial_step;
  } else if (h_last_ > 0.0) {
    h = h_last_;
  } else {
    double d0 = 0, d1 = 0;
    for (int i = 0; i < n; ++i) {
      const double sc = calc_scale(y[i], y[i]);
      d0 += (y[i] / sc) * (y[i] / sc);
      d1 += (k_[0][i] / sc) * (k_[0][i] / sc);
    }
    d0 = std::sqrt(d0 / n);
    d1 = std::sqrt(d1 / n);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = std::min(h0, span);
    for (int i = 0; i < n; ++i) ytmp_[i] = y[i] + h0 * k_[0][i];
    sys.calc_rhs(t + h0, ytmp_.data(), k_[1].data());
    ++sum.rhs_evals;
    double d2 = 0;
    for (int i = 0; i < n; ++i) {
      const double v = (k_[1][i] - k_[0][i]) / calc_scale(y[i], y[i]);
      d2 += v * v;
    }
    d2 = std::sqrt(d2 / n) / h0;
    const double dm = std::max(d1, d2);
    const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 8.0);
    h = std::min(100.0 * h0, h1);
  }
  return std::min({h, opts_.max_step, span});
}

// One step of size h from (t, y) into ynew_, k_[12] = f(t + h, ynew_); returns the scaled error
// estimate of dop853.f (NaN if the state is not finite).
double Dop853::attempt_step(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum) {
  const int n = sys.size();
  for (int s = 1; s < kStages; ++s) {
    for (int i = 0; i < n; ++i) ytmp_[i] = y[i];
    for (int j = 0; j < s; ++j) {
      const double a = h * kA[s][j];
      if (a == 0.0) continue;
      const double* kj = k_[j].data();
      for (int i = 0; i < n; ++i) ytmp_[i] += a * kj[i];
    }
    sys.calc_rhs(t + kC[s] * h, ytmp_.data(), k_[s].data());
  }
  for (int i = 0; i < n; ++i) ynew_[i] = y[i];
  for (int j = 0; j < kStages; ++j) {
    const double b = h * kB[j];
    if (b == 0.0) continue;
    const double* kj = k_[j].data();
    for (int i = 0; i < n; ++i) ynew_[i] += b * kj[i];
  }
  sys.calc_rhs(t + h, ynew_.data(), k_[kStages].data());
  sum.rhs_evals += kStages;
  double e5 = 0.0, e3 = 0.0;
  bool finite = true;
  for (int i = 0; i < n; ++i) {
    double a5 = 0.0, a3 = 0.0;
    for (int j = 0; j < kStages; ++j) {
      a5 += kE5[j] * k_[j][i];
      a3 += kE3[j] * k_[j][i];
    }
    const double sc = calc_scale(y[i], ynew_[i]);
    e5 += (a5 / sc) * (a5 / sc);
    e3 += (a3 / sc) * (a3 / sc);
    finite = finite && std::isfinite(ynew_[i]);
  }
  double den = e5 + 0.01 * e3;
  if (!(den > 0.0)) den = 1.0;
  const double err = std::abs(h) * e5 / std::sqrt(n * den);
  return finite && std::isfinite(err) ? err : std::numeric_limits<double>::quiet_NaN();
}

void Dop853::fill_dense(OdeSystem& sys, double t, double h, const double* y, IntegratorSummary& sum) {
  const int n = sys.size();
  for (int s = kStages + 1; s < kStagesDense; ++s) {
    for (int i = 0; i < n; ++i) ydense_[i] = y[i];
    for (int j = 0; j < s; ++j) {
      const double a = h * kA[s][j];
      if (a == 0.0) continue;
      const double* kj = k_[j].data();
      for (int i = 0; i < n; ++i) ydense_[i] += a * kj[i];
    }
    sys.calc_rhs(t + kC[s] * h, ydense_.data(), k_[s].data());
  }
  sum.rhs_evals += kStagesDense - kStages - 1;
  for (int i = 0; i < n; ++i) {
    const double dy = ynew_[i] - y[i];
    rc_[0][i] = dy;
    rc_[1][i] = h * k_[0][i] - dy;
    rc_[2][i] = 2.0 * dy - h * (k_[0][i] + k_[kStages][i]);
    for (int r = 0; r < 4; ++r) {
      double d = 0.0;
      for (int j = 0; j < kStagesDense; ++j) d += kD[r][j] * k_[j][i];
      rc_[3 + r][i] = h * d;
    }
    ystart_[i] = y[i];
  }
}

// Events: the earliest sign change in the allowed direction over [t, t_new], refined by the
// Illinois method on the dense output. Returns the event index (or -1) and its time in t_ev.
int Dop853::find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev) {
  const int ne = sys.num_events();
  int ev = -1;
  t_ev = t_new;
  if (ne == 0) return ev;
  sys.calc_events(t_new, ynew_.data(), g1_.data());
  for (int e = 0; e < ne; ++e) {
    if (!crosses(g0_[e], g1_[e], sys.event_direction(e))) continue;
    const double tol = std::max(opts_.event_time_tol, 4.0 * std::numeric_limits<double>::epsilon() * std::abs(t_new));
    const double root = numerics::find_crossing_illinois([&](double tc) {
      dense.calc_state(tc, yroot_.data());
      sys.calc_events(tc, yroot_.data(), gt_.data());
      return gt_[e];
    }, t, g0_[e], t_new, g1_[e], tol);
    if (root < t_ev || ev < 0) { t_ev = root; ev = e; }
  }
  return ev;
}

IntegratorSummary Dop853::integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) {
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
  ytmp_.assign(n, 0.0);
  ynew_.assign(n, 0.0);
  ystart_.assign(n, 0.0);
  ydense_.assign(n, 0.0);
  yroot_.assign(n, 0.0);
  const int ne = sys.num_events();
  g0_.assign(ne, 0.0);
  g1_.assign(ne, 0.0);
  gt_.assign(ne, 0.0);

  const double span = t_end - t0;
  double t = t0;
  sum.t = t;
  if (!(span > 0.0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  const bool fixed = opts_.fixed_step > 0.0;
  sys.calc_rhs(t, y, k_[0].data());
  ++sum.rhs_evals;
  if (ne > 0) sys.calc_events(t, y, g0_.data());
  double h = calc_initial_step(sys, t, y, span, sum);

  bool last_rejected = false;
  StiffnessTest stiffness;
  stiffness.boundary = 6.1;
  Dense dense;
  dense.owner = this;
  dense.sys = &sys;
  dense.sum = &sum;
  dense.y = y;
  dense.n = n;
  auto finish = [&](IntegratorStatus st, double t_at, std::string msg = {}) {
    sum.status = st;
    sum.t = t_at;
    sum.message = std::move(msg);
    return sum;
  };
  // Step ratio h_new / h = 0.9 err^(-1/8), kept within [1/3, 6] (dop853.f: fac1 = 0.333, fac2 = 6).
  const auto ratio = [](double err) { return std::clamp(0.9 * std::pow(std::max(err, 1e-300), -1.0 / 8.0), 0.333, 6.0); };
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
      h *= std::min(1.0, ratio(err));
      last_rejected = true;
      ++sum.rejected_steps;
      if (h < 1e-14 * std::max(1.0, std::abs(t)))
        return finish(IntegratorStatus::failure, t, fmt::format("step size underflow at t = {:.9g} s", t));
      continue;
    }
    dense.t0 = t; dense.h = h; dense.t_begin = t; dense.t_end = t + h;
    dense.ready = false;
    ++sum.steps;
    const double t_new = t + h;
    double t_ev;
    const int ev = find_event(sys, t, t_new, dense, t_ev);
    if (ev >= 0) {
      dense.fill();  // before y, the step's start, is overwritten
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
    // k_11 = f(t + h, ytmp_) (the last stage) and k_12 = f(t + h, ynew_).
    const bool stiff = opts_.stop_when_stiff && !fixed && stiffness.update(h, k_[kStages], k_[kStages - 1], ynew_, ytmp_);
    std::copy(ynew_.begin(), ynew_.end(), y);
    std::swap(k_[0], k_[kStages]);  // FSAL
    if (ne > 0) std::swap(g0_, g1_);
    t = t_new;
    if (last) return finish(IntegratorStatus::reached_end, t);
    if (stiff)
      return finish(IntegratorStatus::stiff, t, fmt::format("stiff at t = {:.9g} s (h |lambda| > 6.1 on 15 steps)", t));
    if (!fixed) {
      h = std::min(h * (last_rejected ? std::min(1.0, ratio(err)) : ratio(err)), opts_.max_step);
      h_last_ = h;
      last_rejected = false;
    }
  }
}

}  // namespace truss::integrators
