#include "stages/phase_dynamic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "numerics/illinois.hpp"

namespace truss::stages {

namespace {

// The phase as an ODE: state (q, q', W), dof values each and the drive work. When the model has
// a residual form (PhaseModel::calc_dae_terms), also as the DAE of integrators::DaeForm with the
// model's multipliers mu as algebraic unknowns, residual rows (state v = q'):
//   q' - v,   M v' - r - sum_j mu_j c_j,   W' - F u,   c_j' v' - s_j.
class PhaseOde final : public integrators::OdeSystem, public integrators::DaeForm {
 public:
  PhaseOde(const PhaseModel& m, double creep_speed_m_per_s) : m_(m), n_(m.dof()), creep_(creep_speed_m_per_s) {}
  int size() const override { return 2 * n_ + 1; }
  integrators::DaeForm* dae_form() override { return m_.num_multipliers() >= 0 ? this : nullptr; }
  int num_algebraic() const override { return m_.num_multipliers(); }
  bool calc_residual(double, const double* y, const double* yp, const double* mu, double* res) override {
    if (!m_.calc_dae_terms(y, y + n_, scratch_, terms_)) return false;
    const PhaseDaeTerms& t = terms_;
    const double* acc = yp + n_;
    for (int i = 0; i < n_; ++i) {
      res[i] = yp[i] - y[n_ + i];
      double r = t.diag[i] * acc[i] - t.rhs[i];
      if (i > 0) r += t.sub[i] * acc[i - 1];
      if (i + 1 < n_) r += t.sub[i + 1] * acc[i + 1];
      for (int j = 0; j < t.num_multipliers; ++j) r -= mu[j] * t.c[j][i];
      res[n_ + i] = r;
    }
    const double F = t.drive_multiplier >= 0 ? mu[t.drive_multiplier] : t.drive_force_N;
    res[2 * n_] = yp[2 * n_] - F * t.driven_speed_m_per_s;
    for (int j = 0; j < t.num_multipliers; ++j) {
      double r = -t.s[j];
      for (int i = 0; i < n_; ++i) r += t.c[j][i] * acc[i];
      res[2 * n_ + 1 + j] = r;
    }
    return true;
  }
  // Start guess for IDACalcIC: y' and the multipliers of the direct solve (the rail's lambda, the
  // velocity drive's force), which IDACalcIC then checks against the residual.
  bool calc_initial_guess(double t, const double* y, double* yp, double* mu) override {
    calc_rhs(t, y, yp);
    if (!m_.calc_dae_terms(y, y + n_, scratch_, terms_)) return false;
    acc_.resize(static_cast<std::size_t>(n_));
    const PhasePoint p = m_.calc_point(y, y + n_, acc_.data(), scratch_);
    for (int j = 0; j < terms_.num_multipliers; ++j) mu[j] = j == terms_.drive_multiplier ? p.drive_force_N : p.lambda_N;
    return std::isfinite(yp[0]);
  }
  // Each coordinate's q_i and v_i side by side, then W and the multipliers: positions 2i, 2i + 1,
  // 2n, 2n + 1 + j. By PhaseDaeTerms' locality (phase.hpp) row i of M v' - r couples q, v, v' of
  // coordinates i-1..i+1 (offsets -3..+2) and, for i >= n-2, the multipliers (up to +3 + k); the
  // rows of W and of the constraints couple q, v of coordinates n-2, n-1 (down to -4 - k).
  bool find_band_order(std::vector<int>& order, int& lower, int& upper) const override {
    const int k = m_.num_multipliers();
    order.resize(static_cast<std::size_t>(2 * n_ + 1 + k));
    for (int i = 0; i < n_; ++i) {
      order[static_cast<std::size_t>(2 * i)] = i;
      order[static_cast<std::size_t>(2 * i + 1)] = n_ + i;
    }
    for (int p = 2 * n_; p < 2 * n_ + 1 + k; ++p) order[static_cast<std::size_t>(p)] = p;
    lower = 4 + k;
    upper = k > 0 ? 3 + k : 2;
    return true;
  }
  // The coordinates' smooth lengths from the model; velocities, work and multipliers: unlimited.
  bool calc_smooth_lengths(const double* y, double* len) const override {
    const int total = 2 * n_ + 1 + std::max(m_.num_multipliers(), 0);
    std::fill_n(len, total, std::numeric_limits<double>::infinity());
    return m_.calc_smooth_lengths(y, len);
  }
  // The coordinates' error factors from the model; velocities, work and multipliers: 1.
  bool calc_error_factors(const double* y, double* f) const override {
    std::fill_n(f, 2 * n_ + 1 + std::max(m_.num_multipliers(), 0), 1.0);
    return m_.calc_error_factors(y, f);
  }
  void calc_rhs(double, const double* y, double* dy) override {
    const double power = m_.calc_motion(y, y + n_, dy + n_, scratch_);
    std::copy(y + n_, y + 2 * n_, dy);
    dy[2 * n_] = power;
  }
  // Events: 0 the phase end, 1 the stop of the driven frame, 2 the creep (when a creep speed is
  // given), then the model's stop events.
  int num_base_events() const { return creep_ > 0.0 ? 3 : 2; }
  int num_events() const override { return num_base_events() + m_.num_stop_events(); }
  void calc_events(double, const double* y, double* g) override {
    g[0] = m_.calc_end_gap(y);
    const double u = m_.context().direction * m_.calc_driven_speed_m_per_s(y, y + n_);
    g[1] = u;
    if (creep_ > 0.0) g[2] = u - creep_;
    m_.calc_stop_events(y, y + n_, g + num_base_events());
  }
  int event_direction(int k) const override { return k == 0 || k >= num_base_events() ? +1 : -1; }

 private:
  const PhaseModel& m_;
  int n_;
  double creep_;
  PhaseScratch scratch_;
  PhaseDaeTerms terms_;
  std::vector<double> acc_;  // the initial guess's accelerations
};

// Watches the model's grazing touches (PhaseModel::num_touches) between step ends: a touch whose
// h rises at a step's start and falls at its end, below 0 at both, has a maximum inside; if h >= 0
// there, the touch happened where h first reached 0 (both located on the step's dense output).
class TouchWatch {
 public:
  TouchWatch(const PhaseModel& m, double time_tol)
      : m_(m), n_(m.dof()), tol_(time_tol), h0_(static_cast<std::size_t>(m.num_touches())), r0_(h0_.size()),
        h1_(h0_.size()), r1_(h0_.size()), state_(static_cast<std::size_t>(2 * n_ + 1)) {}
  bool empty() const { return h0_.empty(); }
  void start(const double* q, const double* qdot) { m_.calc_touches(q, qdot, h0_.data(), r0_.data()); }
  // The earliest touch in the step [d.t_begin, d.t_end] whose end state is y1: its index (-1: none)
  // and time t. The step end becomes the start of the next step.
  int find(const integrators::DenseOutput& d, const double* y1, double& t) {
    m_.calc_touches(y1, y1 + n_, h1_.data(), r1_.data());
    int found = -1;
    t = d.t_end;
    for (std::size_t k = 0; k < h0_.size(); ++k) {
      if (!(h0_[k] < 0.0 && h1_[k] < 0.0 && r0_[k] > 0.0 && r1_[k] < 0.0)) continue;
      const auto touch = [&](double tt, bool rate) {
        d.calc_state(tt, state_.data());
        m_.calc_touches(state_.data(), state_.data() + n_, h_.data(), r_.data());
        return rate ? r_[k] : h_[k];
      };
      h_.resize(h0_.size());
      r_.resize(h0_.size());
      const double tol = std::max(tol_, 4.0 * std::numeric_limits<double>::epsilon() * std::abs(d.t_end));
      const double t_max = numerics::find_crossing_illinois([&](double tt) { return touch(tt, true); }, d.t_begin,
                                                             r0_[k], d.t_end, r1_[k], tol);
      const double h_max = touch(t_max, false);
      if (!(h_max >= 0.0)) continue;
      const double tc = numerics::find_crossing_illinois([&](double tt) { return touch(tt, false); }, d.t_begin, h0_[k],
                                                         t_max, h_max, tol);
      if (found < 0 || tc < t) { found = static_cast<int>(k); t = tc; }
    }
    h0_.swap(h1_);
    r0_.swap(r1_);
    return found;
  }

 private:
  const PhaseModel& m_;
  int n_;
  double tol_;
  std::vector<double> h0_, r0_, h1_, r1_, h_, r_, state_;
};

// Feeds the peak brackets with every step end and the history with its grid times; enforces
// the wall-time cap; stops at a grazing touch, with its time and state.
class PhaseObserver final : public integrators::StepObserver {
 public:
  PhaseObserver(const PhaseModel& m, PhaseSinks& sinks, PhaseScratch& scratch, double time_tol)
      : m_(m), sinks_(sinks), scratch_(scratch), n_(m.dof()), touches_(m, time_tol),
        state_(static_cast<std::size_t>(2 * n_ + 1)), sample_(static_cast<std::size_t>(3 * n_)) {}
  bool timed_out = false;
  long point_evals = 0;
  int touch = -1;                    // the touch that stopped the phase (-1: none)
  double touch_t_s = 0;
  std::vector<double> touch_state;   // (q, q', W) there
  void start(const double* q, const double* qdot) { touches_.start(q, qdot); }
  std::chrono::steady_clock::time_point deadline() const override { return sinks_.deadline; }
  bool on_step(const integrators::DenseOutput& d) override {
    double have = NAN;  // the time whose state is in state_
    auto eval = [&](double t, bool history) {
      if (t != have) d.calc_state(t, state_.data());
      have = NAN;
      ++point_evals;
      if (history && sinks_.history.records_frames()) m_.calc_frame_heights(state_.data(), sinks_.history.frame_buffer());
      std::copy(state_.begin(), state_.begin() + 2 * n_, sample_.begin());
      if (!history) return m_.calc_loads(state_.data(), state_.data() + n_, sample_.data() + 2 * n_, scratch_);
      return m_.calc_point(state_.data(), state_.data() + n_, sample_.data() + 2 * n_, scratch_);
    };
    double t1 = d.t_end;
    if (t1 > d.t_begin && !touches_.empty()) {
      d.calc_state(t1, state_.data());
      touch = touches_.find(d, state_.data(), t1);
      if (touch < 0) have = t1;
    }
    if (t1 > d.t_begin) {
      const PhasePoint p = eval(t1, false);  // the peaks' sample: its loads
      sinks_.phase_peaks.feed(t1, p, sample_.data(), 3 * n_);
    }
    const bool in_time = sinks_.history.sample([&](double t) { return eval(t, true); }, d.t_begin, t1, m_.context().bay,
                                               sinks_.deadline);
    if (touch >= 0) {
      touch_t_s = t1;
      touch_state.assign(state_.size(), 0.0);
      d.calc_state(t1, touch_state.data());
      return false;
    }
    // The clock every PhaseSinks::kClockWork state values stepped over the run.
    long& work = sinks_.clock_work ? *sinks_.clock_work : work_;
    work += 2 * n_ + 1;
    const bool read_clock = work >= PhaseSinks::kClockWork;
    if (read_clock) work = 0;
    if (!in_time || (read_clock && std::chrono::steady_clock::now() > sinks_.deadline)) {
      timed_out = true;
      return false;
    }
    return true;
  }

 private:
  const PhaseModel& m_;
  PhaseSinks& sinks_;
  PhaseScratch& scratch_;
  int n_;
  long work_ = 0;
  TouchWatch touches_;
  std::vector<double> state_, sample_;
};

}  // namespace

std::unique_ptr<integrators::OdeSystem> make_phase_ode(const PhaseModel& model, double creep_speed_m_per_s) {
  return std::make_unique<PhaseOde>(model, creep_speed_m_per_s);
}

double DynamicPhaseSolver::calc_creep_speed_m_per_s(const model::DriveParams& d) {
  return kCreepSpeedFraction * d.calc_no_load_screw_speed_rad_per_s() * d.screw_lead_m / (2.0 * std::numbers::pi);
}

PhaseOutcome DynamicPhaseSolver::solve(const PhaseStart& start, PhaseSinks& sinks) {
  const int n = model_.dof();
  const double t = start.t_s;
  PhaseOutcome out;
  PhaseScratch scratch;
  std::vector<double> y(static_cast<std::size_t>(2 * n + 1), 0.0), s0(static_cast<std::size_t>(3 * n));
  std::copy(start.q, start.q + n, y.begin());
  std::copy(start.qdot, start.qdot + n, y.begin() + n);
  std::copy(y.begin(), y.begin() + 2 * n, s0.begin());
  const PhasePoint p_start = model_.calc_point(start.q, start.qdot, s0.data() + 2 * n, scratch);
  ++out.evals;
  sinks.phase_peaks.reset(model_.context().direction);
  sinks.phase_peaks.feed(t, p_start, s0.data(), 3 * n);
  const double u0 = model_.context().direction * model_.calc_driven_speed_m_per_s(start.q, start.qdot);
  if (std::abs(u0) <= 0.0 && !(model_.calc_end_gap_acceleration(s0.data() + 2 * n) > 0.0)) {
    out.reason = PhaseEndReason::cannot_start;
    out.t_end_s = t;
    out.end = p_start;
    return out;
  }
  PhaseOde ode(model_, start.creep_speed_m_per_s);
  PhaseObserver obs(model_, sinks, scratch, options_.event_time_tol);
  obs.start(start.q, start.qdot);
  integrator_.set_options(options_);
  integrators::IntegratorSummary sum = integrator_.integrate(ode, t, t + kHorizon_s, y.data(), &obs);
  if (obs.touch >= 0) {  // a grazing touch, before any event the integrator found in the same step
    y = obs.touch_state;
    sum.t = obs.touch_t_s;
    sum.status = integrators::IntegratorStatus::event;
    const int e = model_.find_touch_event(obs.touch);
    sum.event_index = e < 0 ? 0 : ode.num_base_events() + e;
  }
  out.steps = sum.steps;
  out.rejected_steps = sum.rejected_steps;
  out.evals += sum.rhs_evals + obs.point_evals;
  out.drive_work_J = y[static_cast<std::size_t>(2 * n)];
  out.t_end_s = sum.t;
  const bool reached = sum.status == integrators::IntegratorStatus::event && sum.event_index == 0;
  std::vector<double> qddot(static_cast<std::size_t>(n));
  if (reached) {
    model_.snap_to_end(y.data());  // onto the event surface (|error| < event tolerance)
    out.end = model_.calc_point(y.data(), y.data() + n, qddot.data(), scratch);
    ++out.evals;
  }
  out.end_state.assign(y.begin(), y.begin() + 2 * n);
  // Peaks of the phase: best step-end samples refined on the Hermite interpolant (the quantities
  // that do not change in the phase, not searched), but for the last span of a singular stop.
  const int stop = sum.status == integrators::IntegratorStatus::event ? sum.event_index - ode.num_base_events() : -1;
  if (stop >= 0 && model_.is_singular_stop(stop)) sinks.phase_peaks.end_at_singularity();
  std::vector<double> q(static_cast<std::size_t>(n)), qd(static_cast<std::size_t>(n));
  const unsigned constant = find_constant_quantities(model_.context().kind);
  sinks.peaks.absorb(sinks.phase_peaks, [&](double tt, const HermiteSpan& span) {
    span.calc(tt, q.data(), qd.data());
    ++out.evals;
    return model_.calc_loads(q.data(), qd.data(), qddot.data(), scratch);
  }, 1e-10 * std::max(1.0, out.t_end_s), constant);
  if (reached) return out;
  out.end = model_.calc_point(y.data(), y.data() + n, qddot.data(), scratch);
  out.message = sum.message;
  if (sum.status == integrators::IntegratorStatus::event && sum.event_index >= ode.num_base_events()) {
    out.reason = PhaseEndReason::model_stop;
    out.stop_event = sum.event_index - ode.num_base_events();
  } else if (sum.status == integrators::IntegratorStatus::event && sum.event_index == 2) out.reason = PhaseEndReason::crept_to_rest;
  else if (sum.status == integrators::IntegratorStatus::event && sum.event_index == 1) out.reason = PhaseEndReason::stopped;
  else if (obs.timed_out || sum.status == integrators::IntegratorStatus::deadline) out.reason = PhaseEndReason::wall_time;
  else if (sum.status == integrators::IntegratorStatus::step_limit) out.reason = PhaseEndReason::step_limit;
  else if (sum.status == integrators::IntegratorStatus::reached_end) out.reason = PhaseEndReason::horizon;
  else out.reason = PhaseEndReason::failure;
  return out;
}

}  // namespace truss::stages
