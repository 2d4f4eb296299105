#include "integrators/embedded_rk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "numerics/illinois.hpp"

namespace truss::integrators {

// The accepted step's continuous solution: its end is y1 itself; any other time first fills the
// pair's dense output (once per step, from the step's start y, intact until then).
class EmbeddedRungeKutta::Dense final : public DenseOutput {
 public:
  RkPair* pair = nullptr;
  OdeSystem* sys = nullptr;
  IntegratorSummary* sum = nullptr;
  RkStages* st = nullptr;
  const double* y = nullptr;
  double t0 = 0, h = 0;
  mutable bool ready = false;
  void fill() const {
    if (!ready) sum->rhs_evals += pair->fill_dense(*sys, t0, h, y, *st);
    ready = true;
  }
  void calc_state(double t, double* out) const override {
    if (t == t0 + h) {
      std::copy(st->y1.begin(), st->y1.end(), out);
      return;
    }
    fill();
    pair->calc_dense((t - t0) / h, out);
  }
};

namespace {

bool crosses(double g0, double g1, int dir) {
  if (dir >= 0 && g0 < 0.0 && g1 >= 0.0) return true;
  if (dir <= 0 && g0 > 0.0 && g1 <= 0.0) return true;
  return false;
}

// The step-size controller: the ratio h_new / h after a rejected step, 0.9 err^(-1/q) within
// [ratio_min, 1], and after an accepted one, the PI law (Gustafsson; Hairer's DOPRI5 with beta =
// 0.04; beta = 0, DOP853's elementary controller) within [ratio_min, ratio_max], no growth right
// after a rejection.
class StepControl {
 public:
  explicit StepControl(const RkPairTraits& tr) : tr_(tr), inv_q_(1.0 / tr.order) {}
  double reject(double err) {
    last_rejected_ = true;
    return std::clamp(0.9 * std::pow(err, -inv_q_), tr_.ratio_min, 1.0);
  }
  double accept(double err) {
    const double e = std::max(err, 1e-10);
    const double fac = 0.9 * std::pow(e, -inv_q_ + tr_.pi_beta * 0.75) * std::pow(err_prev_, tr_.pi_beta);
    const double ratio = std::clamp(fac, tr_.ratio_min, last_rejected_ ? 1.0 : tr_.ratio_max);
    err_prev_ = std::max(err, 1e-4);
    last_rejected_ = false;
    return ratio;
  }
  void reject_non_finite() { last_rejected_ = true; }

 private:
  const RkPairTraits& tr_;
  double inv_q_;
  double err_prev_ = 1e-4;  // PI controller memory
  bool last_rejected_ = false;
};

}  // namespace

bool StiffnessTest::update(double h, const std::vector<double>& kb, const std::vector<double>& ka,
                           const std::vector<double>& yb, const std::vector<double>& ya) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < kb.size(); ++i) {
    num += (kb[i] - ka[i]) * (kb[i] - ka[i]);
    den += (yb[i] - ya[i]) * (yb[i] - ya[i]);
  }
  if (!(den > 0.0)) return false;
  if (h * std::sqrt(num / den) > boundary) {
    non_stiff = 0;
    return ++stiff_steps >= 15;
  }
  if (++non_stiff >= 6) stiff_steps = 0;
  return false;
}

EmbeddedRungeKutta::EmbeddedRungeKutta(const IntegratorOptions& opts, std::unique_ptr<RkPair> pair)
    : opts_(opts), pair_(std::move(pair)) {}

void EmbeddedRungeKutta::resize(int n, int num_events) {
  st_.k.resize(static_cast<std::size_t>(pair_->traits().num_stages));
  for (auto& k : st_.k) k.assign(n, 0.0);
  st_.ytmp.assign(n, 0.0);
  st_.y1.assign(n, 0.0);
  yev_.assign(n, 0.0);
  pair_->resize(n);
  g0_.assign(num_events, 0.0);
  g1_.assign(num_events, 0.0);
  gt_.assign(num_events, 0.0);
}

// Initial step: the fixed or asked step, else the last accepted step of the previous call, else
// Hairer's heuristic (Solving ODEs I, II.4) with one explicit Euler probe (st_.k[0] holds f(t, y)).
double EmbeddedRungeKutta::calc_initial_step(OdeSystem& sys, double t, const double* y, double span,
                                             IntegratorSummary& sum) {
  const int n = sys.size();
  const ErrorScale scale{opts_.atol, opts_.rtol};
  double h;
  if (opts_.fixed_step > 0.0) {
    h = opts_.fixed_step;
  } else if (opts_.initial_step > 0.0) {
    h = opts_.initial_step;
  } else if (h_last_ > 0.0) {
    h = h_last_;
  } else {
    const std::vector<double>& f0 = st_.k[0];
    double d0 = 0, d1 = 0;
    for (int i = 0; i < n; ++i) {
      const double sc = scale(y[i], y[i]);
      d0 += (y[i] / sc) * (y[i] / sc);
      d1 += (f0[i] / sc) * (f0[i] / sc);
    }
    d0 = std::sqrt(d0 / n);
    d1 = std::sqrt(d1 / n);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = std::min(h0, span);
    for (int i = 0; i < n; ++i) st_.ytmp[i] = y[i] + h0 * f0[i];
    sys.calc_rhs(t + h0, st_.ytmp.data(), st_.k[1].data());
    ++sum.rhs_evals;
    double d2 = 0;
    for (int i = 0; i < n; ++i) {
      const double v = (st_.k[1][i] - f0[i]) / scale(y[i], y[i]);
      d2 += v * v;
    }
    d2 = std::sqrt(d2 / n) / h0;
    const double dm = std::max(d1, d2);
    const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / pair_->traits().order);
    h = std::min(100.0 * h0, h1);
  }
  return std::min({h, opts_.max_step, span});
}

// Events: the earliest sign change in the allowed direction over [t, t_new], refined by the
// Illinois method on the dense output. Returns the event index (or -1) and its time in t_ev.
int EmbeddedRungeKutta::find_event(OdeSystem& sys, double t, double t_new, const DenseOutput& dense, double& t_ev) {
  const int ne = sys.num_events();
  int ev = -1;
  t_ev = t_new;
  if (ne == 0) return ev;
  sys.calc_events(t_new, st_.y1.data(), g1_.data());
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

IntegratorSummary EmbeddedRungeKutta::integrate(OdeSystem& sys, double t0, double t_end, double* y,
                                                StepObserver* observer) {
  IntegratorSummary sum;
  if (const std::string bad = opts_.validate(); !bad.empty()) {
    sum.t = t0;
    sum.status = IntegratorStatus::failure;
    sum.message = "invalid integrator options: " + bad;
    return sum;
  }
  const RkPairTraits& tr = pair_->traits();
  resize(sys.size(), sys.num_events());
  const int ne = sys.num_events();

  const double span = t_end - t0;
  double t = t0;
  sum.t = t;
  if (!(span > 0.0)) { sum.status = IntegratorStatus::reached_end; return sum; }
  const bool fixed = opts_.fixed_step > 0.0;
  sys.calc_rhs(t, y, st_.k[0].data());
  ++sum.rhs_evals;
  if (ne > 0) sys.calc_events(t, y, g0_.data());
  double h = calc_initial_step(sys, t, y, span, sum);

  const ErrorScale scale{opts_.atol, opts_.rtol};
  StepControl control(tr);
  StiffnessTest stiffness;
  stiffness.boundary = tr.stiff_boundary;
  Dense dense;
  dense.pair = pair_.get();
  dense.sys = &sys;
  dense.sum = &sum;
  dense.st = &st_;
  dense.y = y;
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
    const double err = pair_->attempt_step(sys, t, h, y, st_, scale);
    sum.rhs_evals += tr.rhs_per_step;
    if (!std::isfinite(err)) {
      if (fixed || h < 1e-14 * std::max(1.0, std::abs(t)))
        return finish(IntegratorStatus::failure, t, fmt::format("non-finite state at t = {:.9g} s", t));
      h *= 0.25; control.reject_non_finite(); ++sum.rejected_steps;
      continue;
    }
    if (!fixed && err > 1.0) {
      h *= control.reject(err);
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
      std::copy(st_.y1.begin(), st_.y1.end(), y);
      return finish(IntegratorStatus::stopped_by_observer, t_new);
    }
    // The last stage f(t + h, ytmp) and f(t + h, y1): h |lambda| ~ h |k_fsal - k_last| / |y1 - ytmp|.
    const bool stiff = opts_.stop_when_stiff && !fixed &&
                       stiffness.update(h, st_.k[tr.fsal], st_.k[tr.last_stage], st_.y1, st_.ytmp);
    std::copy(st_.y1.begin(), st_.y1.end(), y);
    std::swap(st_.k[0], st_.k[tr.fsal]);  // FSAL
    if (ne > 0) std::swap(g0_, g1_);
    t = t_new;
    if (last) return finish(IntegratorStatus::reached_end, t);
    if (stiff)
      return finish(IntegratorStatus::stiff, t,
                    fmt::format("stiff at t = {:.9g} s (h |lambda| > {} on 15 steps)", t, tr.stiff_boundary));
    if (!fixed) {
      h = std::min(h * control.accept(err), opts_.max_step);
      h_last_ = h;
    }
  }
}

}  // namespace truss::integrators
