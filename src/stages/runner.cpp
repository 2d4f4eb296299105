#include "stages/runner.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <numbers>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>

#include "integrators/cvode_integrator.hpp"
#include "integrators/dopri54.hpp"
#include "model/bay.hpp"
#include "model/frames.hpp"
#include "model/rail.hpp"

namespace truss::stages {

using namespace truss::model;
using sim::RunResult;
using sim::RunStatus;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Extremum {
  double value = -kInf;
  double t = kNaN;
  int bay = 0;
  bool offer(double v, double time, int b) {
    if (v > value) { value = v; t = time; bay = b; return true; }
    return false;
  }
};

// Brent's method (golden section with parabolic steps) for the maximum of f on [a, b].
template <class F>
std::pair<double, double> maximize_brent(F&& f, double a, double b, double xtol) {
  const double cgold = 0.3819660112501051;
  double x = a + cgold * (b - a), w = x, v = x;
  double fx = -f(x), fw = fx, fv = fx;
  double d = 0.0, e = 0.0;
  for (int it = 0; it < 100; ++it) {
    const double xm = 0.5 * (a + b);
    const double tol1 = xtol + 1e-12 * std::abs(x), tol2 = 2.0 * tol1;
    if (std::abs(x - xm) <= tol2 - 0.5 * (b - a)) break;
    bool golden = true;
    if (std::abs(e) > tol1) {
      const double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::abs(q);
      const double etemp = e;
      e = d;
      if (!(std::abs(p) >= std::abs(0.5 * q * etemp) || p <= q * (a - x) || p >= q * (b - x))) {
        d = p / q;
        const double u = x + d;
        if (u - a < tol2 || b - u < tol2) d = (xm - x) >= 0 ? tol1 : -tol1;
        golden = false;
      }
    }
    if (golden) {
      e = (x >= xm) ? a - x : b - x;
      d = cgold * e;
    }
    const double u = std::abs(d) >= tol1 ? x + d : x + (d >= 0 ? tol1 : -tol1);
    const double fu = -f(u);
    if (fu <= fx) {
      if (u >= x) a = x; else b = x;
      v = w; fv = fw; w = x; fw = fx; x = u; fx = fu;
    } else {
      if (u < x) a = u; else b = u;
      if (fu <= fw || w == x) { v = w; fv = fw; w = u; fw = fu; }
      else if (fu <= fv || v == x || v == w) { v = u; fv = fu; }
    }
  }
  return {x, -fx};
}

// Adaptive Gauss-Kronrod (7, 15) quadrature.
template <class F>
double integrate_gk15(F&& f, double a, double b, double abs_tol, int depth = 0) {
  static constexpr double xgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                    0.207784955007898467600689403773245, 0.0};
  static constexpr double wgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
  static constexpr double wg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                   0.381830050505118944950369775488975, 0.417959183673469387755102040816327};
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  const double fc = f(c);
  double k = wgk[7] * fc, g = wg[3] * fc;
  for (int j = 0; j < 7; ++j) {
    const double f1 = f(c - h * xgk[j]), f2 = f(c + h * xgk[j]);
    k += wgk[j] * (f1 + f2);
    if (j % 2 == 1) g += wg[j / 2] * (f1 + f2);
  }
  k *= h; g *= h;
  if (std::abs(k - g) <= abs_tol || depth >= 30) return k;
  return integrate_gk15(f, a, c, 0.5 * abs_tol, depth + 1) + integrate_gk15(f, c, b, 0.5 * abs_tol, depth + 1);
}

// Quantities whose extremes a run reports.
enum Q { kForce, kNegForce, kPin, kTension, kSpeed, kQCount };

struct Sample {
  double t = 0;
  PhasePoint p;
};

// State between two samples of a phase: quintic Hermite interpolation of q from (q, q', q'')
// at both ends, error O(h^6) in q and O(h^5) in q', below the integrator's own error.
struct HermiteSpan {
  const Sample* a;
  const Sample* b;
  void calc(double t, double& q, double& qd) const {
    const double h = b->t - a->t, s = (t - a->t) / h, s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
    const double qa = a->p.q, va = h * a->p.qdot, aa = h * h * a->p.qddot;
    const double qb = b->p.q, vb = h * b->p.qdot, ab = h * h * b->p.qddot;
    q = (1 - 10 * s3 + 15 * s4 - 6 * s5) * qa + (s - 6 * s3 + 8 * s4 - 3 * s5) * va +
        (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * aa + (10 * s3 - 15 * s4 + 6 * s5) * qb +
        (-4 * s3 + 7 * s4 - 3 * s5) * vb + (0.5 * s3 - s4 + 0.5 * s5) * ab;
    qd = ((-30 * s2 + 60 * s3 - 30 * s4) * qa + (1 - 18 * s2 + 32 * s3 - 15 * s4) * va +
          (s - 4.5 * s2 + 6 * s3 - 2.5 * s4) * aa + (30 * s2 - 60 * s3 + 30 * s4) * qb +
          (-12 * s2 + 28 * s3 - 15 * s4) * vb + (1.5 * s2 - 4 * s3 + 2.5 * s4) * ab) / h;
  }
};

double quantity(int q, const PhasePoint& p, double direction) {
  switch (q) {
    case kForce: return p.drive_force_N;
    case kNegForce: return -p.drive_force_N;
    case kPin: return p.pin_force_N;
    case kTension: return p.diagonal_tension_N;
    default: return direction * p.u_m_per_s;
  }
}

// Follows the samples of one phase in time order and keeps, for each quantity, its best sample
// with the neighbours that bracket it; refine() then maximises between the neighbours.
class PhaseBrackets {
 public:
  explicit PhaseBrackets(double direction) : direction_(direction) {}
  void feed(double t, const PhasePoint& p) {
    for (int q = 0; q < kQCount; ++q) {
      B& b = b_[static_cast<std::size_t>(q)];
      const double v = quantity(q, p, direction_);
      if (v > b.value) {
        b.value = v;
        b.prev = has_last_ ? last_ : Sample{t, p};
        b.best = {t, p};
        b.next = b.best;
        b.want_next = true;
      } else if (b.want_next) {
        b.next = {t, p};
        b.want_next = false;
      }
    }
    last_ = {t, p};
    has_last_ = true;
    max_rail_residual = std::max(max_rail_residual, p.rail_residual_m);
  }
  // eval(t, span) gives the phase point at t inside the span [a, b] of two consecutive samples.
  template <class Eval>
  void refine(int q, Eval&& eval, double xtol, double& value, double& time) const {
    const B& b = b_[static_cast<std::size_t>(q)];
    value = b.value;
    time = b.best.t;
    if (!std::isfinite(b.value)) return;
    for (const HermiteSpan span : {HermiteSpan{&b.prev, &b.best}, HermiteSpan{&b.best, &b.next}}) {
      const double len = span.b->t - span.a->t;
      if (!(len > 0.0)) continue;
      // A best sample at a kink or at the phase end is often the maximum itself: if the quantity
      // falls just inside the span, the span holds nothing higher (it is bracketed by the grid).
      const bool best_is_a = span.a == &b.best;
      const double probe_t = best_is_a ? span.a->t + 1e-6 * len : span.b->t - 1e-6 * len;
      if (quantity(q, eval(probe_t, span), direction_) < b.value) continue;
      auto [tm, vm] = maximize_brent([&](double t) { return quantity(q, eval(t, span), direction_); },
                                     span.a->t, span.b->t, std::max(xtol, 1e-9 * len));
      if (vm > value) { value = vm; time = tm; }
    }
  }
  double best(int q) const { return b_[static_cast<std::size_t>(q)].value; }
  double max_rail_residual = 0.0;

 private:
  struct B {
    double value = -kInf;
    Sample prev, best, next;
    bool want_next = false;
  };
  std::array<B, kQCount> b_;
  Sample last_;
  bool has_last_ = false;
  double direction_;
};

struct Trackers {
  std::array<Extremum, kQCount> run;   // run-wide
  Extremum stage_force, stage_pin;     // per stage
  double max_rail_residual = 0.0;
  int bay = 0;
  Extremum& target(int q) {
    if (q == kForce) return stage_force;
    if (q == kPin) return stage_pin;
    return run[static_cast<std::size_t>(q)];
  }
  // Refines each quantity of a finished phase whose best sample could beat the record.
  template <class Eval>
  void absorb(const PhaseBrackets& pb, Eval&& eval, double xtol) {
    max_rail_residual = std::max(max_rail_residual, pb.max_rail_residual);
    for (int q = 0; q < kQCount; ++q) {
      Extremum& tr = target(q);
      if (!(pb.best(q) > tr.value) && std::isfinite(tr.value)) continue;
      double v, t;
      pb.refine(q, eval, xtol, v, t);
      tr.offer(v, t, bay);
    }
  }
};

struct History {
  sim::TimeHistory* out = nullptr;
  double step = 0.0;
  long next = 0;
  const DriveParams* drive = nullptr;
  double next_time() const { return static_cast<double>(next) * step; }
  // Samples the grid times in [t0, t1).
  template <class Eval>
  void sample(Eval&& eval, double t0, double t1, int bay) {
    if (!out || step <= 0.0) return;
    while (true) {
      const double t = next_time();
      if (t < t0 - 1e-12 * std::max(1.0, t0)) { ++next; continue; }
      if (t >= t1) break;
      push(t, eval(std::clamp(t, t0, t1)), bay);
      ++next;
    }
  }
  void push(double t, const PhasePoint& p, int bay) {
      out->t_s.push_back(t);
      out->bay.push_back(bay);
      out->y_driven_m.push_back(p.y_driven_m);
      out->y_lower_m.push_back(p.y_lower_m);
      out->hinge_x_m.push_back(p.hinge_x_m);
      out->hinge_y_m.push_back(p.hinge_y_m);
      out->drive_force_N.push_back(p.drive_force_N);
      out->drive_torque_Nm.push_back(drive->calc_torque_Nm(p.drive_force_N));
      out->pin_force_N.push_back(p.pin_force_N);
      out->diagonal_tension_N.push_back(p.diagonal_tension_N);
      out->driven_speed_m_per_s.push_back(p.u_m_per_s);
  }
};

// Phase as an ODE: state (q, q', W) with W the drive work; events: phase end, stall.
class PhaseOde : public integrators::OdeSystem {
 public:
  PhaseOde(const HeldPhase& ph, double q_end, double sign_q, double direction)
      : ph_(ph), q_end_(q_end), sign_q_(sign_q), direction_(direction) {}
  int size() const override { return 3; }
  void calc_rhs(double, const double* y, double* dy) override {
    const PhasePoint p = ph_.calc_point(y[0], y[1]);
    dy[0] = y[1];
    dy[1] = p.qddot;
    dy[2] = p.drive_force_N * p.u_m_per_s;
  }
  // Motor mode adds a creep stall: the speed-torque line damps the motion, so a drive that is too
  // weak brings the mast to rest asymptotically at an equilibrium short of the lock, and the speed
  // never crosses zero. Below kCreepSpeedFraction of the no-load screw speed the mast has stopped
  // for any engineering purpose (the rest of the stage would take ~1e6 times its nominal time).
  static constexpr double kCreepSpeedFraction = 1e-6;
  int num_events() const override { return ph_.context().drive.law == DriveLaw::motor ? 3 : 2; }
  void calc_events(double, const double* y, double* g) override {
    g[0] = sign_q_ * (y[0] - q_end_);
    const double u = direction_ * calc_u(y[0], y[1]);
    g[1] = u;
    if (ph_.context().drive.law == DriveLaw::motor) g[2] = u - creep_speed_m_per_s();
  }
  int event_direction(int k) const override { return k == 0 ? +1 : -1; }
  double creep_speed_m_per_s() const {
    const DriveParams& d = ph_.context().drive;
    return kCreepSpeedFraction * d.no_load_speed_rad_per_s * d.screw_lead_m / (2.0 * std::numbers::pi);
  }
  double calc_u(double q, double qdot) const {
    if (ph_.context().kind == PhaseKind::open) return qdot;
    return calc_on_rail(ph_.context().mast->rail, ph_.strut_length_m(), q).dY * qdot;
  }

 private:
  const HeldPhase& ph_;
  double q_end_, sign_q_, direction_;
};

class PhaseObserver : public integrators::StepObserver {
 public:
  PhaseObserver(const HeldPhase& ph, PhaseBrackets& br, History& hist, int bay,
                std::chrono::steady_clock::time_point deadline)
      : ph_(ph), br_(br), hist_(hist), bay_(bay), deadline_(deadline) {}
  bool timed_out = false;
  long point_evals = 0;
  bool on_step(const integrators::DenseOutput& d) override {
    double state[3];
    auto eval = [&](double t) {
      d.calc_state(t, state);
      ++point_evals;
      return ph_.calc_point(state[0], state[1]);
    };
    const double t1 = d.t_end;
    if (t1 > d.t_begin) br_.feed(t1, eval(t1));
    hist_.sample(eval, d.t_begin, t1, bay_);
    if (std::chrono::steady_clock::now() > deadline_) { timed_out = true; return false; }
    return true;
  }

 private:
  const HeldPhase& ph_;
  PhaseBrackets& br_;
  History& hist_;
  int bay_;
  std::chrono::steady_clock::time_point deadline_;
};

// y-space mass matrix of frames (m-1, m) with bay m written in frame heights (regular off the
// lock): used for the rail-entry and rail-exit impacts.
struct TwoFrameMass {
  double ll = 0, ml = 0, mm = 0;
};
TwoFrameMass calc_two_frame_mass(const MastParams& mast, const StageSpec& s, double y_lower, double y_driven) {
  ActiveFrames a;
  a.lo = s.bay - 1;
  a.m = s.bay;
  a.locked_mass_kg = s.locked_mass_kg;
  a.panel_height_offset_m = s.panel_height_offset_m;
  FrameSystem sys;
  const double y[3] = {0.0, y_lower, y_driven};
  const double v[3] = {0.0, 0.0, 0.0};
  if (s.bay >= 2) calc_frame_system(mast, a, y, v, s.bay - 2, sys);
  else calc_frame_system(mast, a, y + 1, v + 1, s.bay - 1, sys);
  return {sys.diag[0], sys.sub[1], sys.diag[1]};
}


}  // namespace

sim::RunResult run_held_stages(const MastParams& mast, const std::vector<StageSpec>& stages,
                               const RunnerOptions& opts) {
  const auto wall_start = std::chrono::steady_clock::now();
  const auto deadline = wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                         std::chrono::duration<double>(opts.max_wall_time_s));
  RunResult r;
  const int n = mast.n_bays();
  r.n_bays = n;
  const DriveParams& drive = opts.drive;
  const double dir = drive.direction;
  const bool kinematic = drive.law == DriveLaw::velocity;
  r.direction = dir > 0 ? "deploy" : "retract";
  r.drive_mode = drive.law == DriveLaw::velocity ? "velocity" : drive.law == DriveLaw::torque ? "torque" : "motor";
  r.bays.resize(static_cast<std::size_t>(n));
  for (int i = 1; i <= n; ++i) r.bays[static_cast<std::size_t>(i - 1)].bay = i;

  // Potential of bays in their stowed (D = 0) and locked (D = 2 l) states, prefix/suffix sums.
  std::vector<double> U_stowed_prefix(n + 1, 0.0), U_locked_suffix(n + 2, 0.0);
  for (int i = 1; i <= n; ++i) {
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    U_stowed_prefix[i] = U_stowed_prefix[i - 1] + calc_bay_potential_J(mast.bay(i), b2, 0.0);
  }
  for (int i = n; i >= 1; --i) {
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    U_locked_suffix[i] = U_locked_suffix[i + 1] + calc_bay_potential_J(mast.bay(i), b2, 2.0 * mast.bay(i).strut_length_m);
  }
  // Whole-mast potential at a point of a stage: locked bays above, moving bays, stowed below.
  auto total_potential = [&](const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p) {
    const int first_moving = ph.kind == PhaseKind::on_rail ? std::max(s.bay - 1, 1) : s.bay;
    return U_locked_suffix[s.bay + 1] + p.potential_energy_J + U_stowed_prefix[first_moving - 1];
  };
  r.potential_energy_start_J = dir > 0 ? U_stowed_prefix[n] : U_locked_suffix[1];

  Trackers tr;
  History hist;
  hist.out = opts.output_step_s > 0.0 ? &r.history : nullptr;
  hist.step = opts.output_step_s;
  hist.drive = &drive;

  std::unique_ptr<integrators::Integrator> integ;
  if (!kinematic) {
    if (opts.integrator == IntegratorChoice::cvode) integ = std::make_unique<integrators::CvodeIntegrator>(opts.integration);
    else integ = std::make_unique<integrators::DormandPrince54>(opts.integration);
  }

  double t = 0.0;
  double u = 0.0;            // driven-frame velocity carried between stages
  double xi = 0.0;           // hinge speed carried between phases
  long evals = 0;
  long steps_left = opts.max_steps;
  PhasePoint last;           // last evaluated point of the run
  const StageSpec* last_stage = nullptr;
  const PhaseSpec* last_phase = nullptr;
  bool failed = false;
  double ke_end = 0.0;
  auto fail = [&](RunStatus st, std::string msg) {
    r.status = st;
    r.message = std::move(msg);
    failed = true;
  };

  for (const StageSpec& s : stages) {
    if (failed) break;
    const int m = s.bay;
    sim::BayResult& br = r.bays[static_cast<std::size_t>(m - 1)];
    tr.bay = m;
    tr.stage_force = Extremum{};
    tr.stage_pin = Extremum{};
    const double l = mast.bay(m).strut_length_m;
    const double c = mast.rail.cot_beta();

    // --- stage start --------------------------------------------------------------------------
    if (s.start == StageStart::from_rest_or_kick && kinematic) {
      // Impulsive start of the driven part from rest (MODEL.md 4): lossless ramp of the drive,
      // work P v / 2 = its kinetic energy.
      PhaseContext ctx{&mast, PhaseKind::open, m, 0.0, s.locked_mass_kg, s.panel_height_offset_m, drive};
      const PhasePoint p0 = HeldPhase(ctx).calc_point(s.phases[0].q_start, dir * drive.speed_m_per_s);
      ++evals;
      u = dir * drive.speed_m_per_s;
      r.start_drive_impulse_Ns = p0.mass_yy * u;
      r.drive_work_impulses_J += 0.5 * p0.mass_yy * u * u;
    }
    if (s.start == StageStart::unlock) {
      PhaseContext ctx{&mast, PhaseKind::on_rail, m, 0.0, s.locked_mass_kg, s.panel_height_offset_m, drive};
      const PhasePoint p0 = HeldPhase(ctx).calc_point(0.0, 0.0);
      ++evals;
      double loss = 0.0;
      if (kinematic) {
        if (m == stages.front().bay) {  // the whole mast starts moving: lossless drive ramp
          u = dir * drive.speed_m_per_s;
          r.start_drive_impulse_Ns = p0.mass_yy * u;
          r.drive_work_impulses_J += 0.5 * p0.mass_yy * u * u;
        }
        // The hinge must leave at the rail's speed: xi = -u / c; drive keeps u (MODEL.md 2).
        xi = -u / c;
        const double Lambda = p0.mass_xx * xi / c;
        const double Pd = -Lambda;
        const double W = Pd * u;
        r.drive_work_impulses_J += W;
        loss = W - 0.5 * p0.mass_xx * xi * xi;
      } else {
        // Plastic impact with the rail: M dv = grad f^T Lambda, grad f . v+ = 0, grad f = (1, c).
        const double Lambda = -u / (1.0 / p0.mass_yy + c * c / p0.mass_xx);
        const double du = Lambda / p0.mass_yy;
        xi = c * Lambda / p0.mass_xx;
        loss = 0.5 * (p0.mass_yy * du * du + p0.mass_xx * xi * xi);
        u += du;
      }
      br.latch_energy_J = loss;
      br.lock_time_s = t;
      r.energy_lost_J += loss;
    }

    // --- phases ----------------------------------------------------------------------------------
    for (std::size_t ip = 0; ip < s.phases.size() && !failed; ++ip) {
      const PhaseSpec& ph = s.phases[ip];
      PhaseContext ctx{&mast, ph.kind, m, ph.lower_held_height_m, s.locked_mass_kg, s.panel_height_offset_m, drive};
      const HeldPhase phase(ctx);
      const double q0 = ph.q_start;
      double qdot0 = ph.kind == PhaseKind::open ? u : xi;
      const double sign_q = ph.q_end > ph.q_start ? 1.0 : -1.0;
      double t_end_phase = t;
      PhasePoint p_end;
      PhaseBrackets brackets(dir);

      if (kinematic) {
        // Closed-form kinematics: the driven frame moves at dir * v; y_m is linear in time.
        const double v = drive.speed_m_per_s;
        double y_begin, y_finish;
        if (ph.kind == PhaseKind::open) { y_begin = ph.q_start; y_finish = ph.q_end; }
        else {
          y_begin = calc_on_rail(mast.rail, l, ph.q_start).Y;
          y_finish = calc_on_rail(mast.rail, l, ph.q_end).Y;
        }
        const double duration = std::abs(y_finish - y_begin) / v;
        const double t0 = t, t1 = t + duration;
        auto eval = [&, t0, t1](double tt) {
          ++evals;
          tt = std::clamp(tt, t0, t1);
          if (ph.kind == PhaseKind::open) {
            // distance from the phase end, measured from the nearer end for exactness
            const double y = (tt - t0 <= t1 - tt) ? y_begin + dir * v * (tt - t0) : y_finish - dir * v * (t1 - tt);
            return phase.calc_point(y, dir * v);
          }
          // travel to the lock, exact near it: deploy ends at the lock, retraction starts there
          const double e = dir > 0 ? v * (t1 - tt) : v * (tt - t0);
          const double x = calc_x_on_rail_from_travel(mast.rail, l, e);
          const OnRailKinematics kin = calc_on_rail(mast.rail, l, x);
          return phase.calc_point(x, dir * v / kin.dY);
        };
        // Smooth pieces: split where bay m's diagonals become taut (a kink of the force).
        std::vector<double> cuts{t0, t1};
        const double b2 = calc_diagonal_offset_sq_m2(mast.frame(m - 1), mast.frame(m));
        const double Dt = calc_taut_opening_m(mast.bay(m), b2);
        if (Dt > 0.0) {
          double y_taut = kNaN;
          if (ph.kind == PhaseKind::open) y_taut = ph.lower_held_height_m + Dt;
          else if (Dt < 2.0 * l) y_taut = calc_on_rail(mast.rail, l, std::sqrt(l * l - 0.25 * Dt * Dt)).Y;
          if (std::isfinite(y_taut)) {
            const double tc = t0 + (y_taut - y_begin) / (dir * v);
            if (tc > t0 && tc < t1) cuts.insert(cuts.begin() + 1, tc);
          }
        }
        const int ns = std::max(3, opts.peak_samples_per_piece);
        double work = 0.0;
        for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
          const double a = cuts[k], b = cuts[k + 1];
          double f_scale = 1.0;
          for (int i = (k == 0 ? 0 : 1); i < ns; ++i) {
            const double ti = a + (b - a) * i / (ns - 1);
            const PhasePoint pi = eval(ti);
            brackets.feed(ti, pi);
            f_scale = std::max(f_scale, std::abs(pi.drive_force_N));
          }
          // Drive work of the smooth motion: integral of F u dt, F from inverse dynamics.
          work += integrate_gk15([&](double tt) { const PhasePoint p = eval(tt); return p.drive_force_N * p.u_m_per_s; },
                                 a, b, 1e-11 * f_scale * v * (b - a));  // |K15 - G7| bound: K15 is far better
        }
        tr.absorb(brackets, [&](double tt, const HermiteSpan&) { return eval(tt); }, 1e-12 * std::max(1.0, t1));
        r.drive_work_smooth_J += work;
        hist.sample(eval, t0, t1, m);
        t_end_phase = t1;
        p_end = eval(t1);
        p_end.q = ph.q_end;  // the event is exact in closed form
      } else {
        // Time stepping with events: the phase end (rising g0) and a stall (falling g1).
        PhaseOde ode(phase, ph.q_end, sign_q, dir);
        PhaseObserver obs(phase, brackets, hist, m, deadline);
        double y[3] = {q0, qdot0, 0.0};
        const PhasePoint p_start = phase.calc_point(q0, qdot0);
        ++evals;
        brackets.feed(t, p_start);
        if (std::abs(dir * ode.calc_u(q0, qdot0)) <= 0.0 && !(sign_q * p_start.qddot > 0.0)) {
          fail(RunStatus::stall, fmt::format("stall: the drive cannot move the mast at t = {:.9g} s in the stage of bay {} "
                                             "(drive force {:.6g} N)", t, m, p_start.drive_force_N));
          last = p_start; last_stage = &s; last_phase = &ph;
          break;
        }
        integrators::IntegratorOptions io = opts.integration;
        io.max_steps = std::max(1L, steps_left);
        integrators::IntegratorSummary sum;
        if (opts.integrator == IntegratorChoice::cvode) sum = integrators::CvodeIntegrator(io).integrate(ode, t, t + 1e7, y, &obs);
        else {
          auto& dp = static_cast<integrators::DormandPrince54&>(*integ);
          dp.set_options(io);
          sum = dp.integrate(ode, t, t + 1e7, y, &obs);
        }
        steps_left -= sum.steps;
        r.steps += sum.steps;
        r.rejected_steps += sum.rejected_steps;
        evals += sum.rhs_evals + obs.point_evals;
        r.drive_work_smooth_J += y[2];
        t_end_phase = sum.t;
        if (sum.status == integrators::IntegratorStatus::event && sum.event_index == 0) {
          y[0] = ph.q_end;  // snap the coordinate onto the event surface (|error| < event tolerance)
          p_end = phase.calc_point(y[0], y[1]);
          ++evals;
        }
        // Peaks of the phase: best step-end samples refined on the Hermite interpolant.
        long refine_evals = 0;
        tr.absorb(brackets, [&](double tt, const HermiteSpan& span) {
          double q, qd;
          span.calc(tt, q, qd);
          ++refine_evals;
          return phase.calc_point(q, qd);
        }, 1e-10 * std::max(1.0, t_end_phase));
        evals += refine_evals;
        if (!(sum.status == integrators::IntegratorStatus::event && sum.event_index == 0)) {
          p_end = phase.calc_point(y[0], y[1]);
          last = p_end; last_stage = &s; last_phase = &ph;
          t = t_end_phase;
          if (sum.status == integrators::IntegratorStatus::event && sum.event_index == 2)
            fail(RunStatus::stall, fmt::format("stall: the driven frame crept to rest (speed below {:.3g} m/s) at y = {:.9g} m, "
                                               "t = {:.9g} s, in the stage of bay {} before its {}: the motor's stall torque "
                                               "balances the mast short of the {}", ode.creep_speed_m_per_s(), p_end.y_driven_m,
                                               t, m, dir > 0 ? "lock" : "end", dir > 0 ? "lock" : "end"));
          else if (sum.status == integrators::IntegratorStatus::event && sum.event_index == 1)
            fail(RunStatus::stall, fmt::format("stall: the driven frame stopped at y = {:.9g} m, t = {:.9g} s, in the stage "
                                               "of bay {} before its {}", p_end.y_driven_m, t, m,
                                               dir > 0 ? "lock" : "end"));
          else if (obs.timed_out)
            fail(RunStatus::wall_time_limit, fmt::format("wall-time cap of {} s reached at t = {:.9g} s (bay {})", opts.max_wall_time_s, t, m));
          else if (sum.status == integrators::IntegratorStatus::step_limit || sum.status == integrators::IntegratorStatus::reached_end)
            fail(RunStatus::step_limit, fmt::format("step cap of {} steps reached at t = {:.9g} s (bay {})", opts.max_steps, t, m));
          else
            fail(RunStatus::step_limit, fmt::format("integrator failure at t = {:.9g} s (bay {}): {}", t, m, sum.message));
          break;
        }
      }
      t = t_end_phase;
      last = p_end; last_stage = &s; last_phase = &ph;

      // --- the event that ends the phase -------------------------------------------------------------
      const double u_end = p_end.u_m_per_s;
      switch (ph.end) {
        case PhaseEnd::rail_entry: {
          // Plastic impact of the held lower frame with the rail (MODEL.md 2), in frame heights.
          const TwoFrameMass M = calc_two_frame_mass(mast, s, ph.lower_held_height_m, p_end.y_driven_m);
          const double x = s.entry_hinge_x_m, D = p_end.y_driven_m - ph.lower_held_height_m;
          const double Jl = 0.5 + c * D / (4.0 * x), Jm = 0.5 - c * D / (4.0 * x);
          double dw, du, Lambda, Pd = 0.0;
          if (kinematic) {
            du = 0.0;
            dw = -Jm * u_end / Jl;
            Lambda = M.ll * dw / Jl;
            Pd = M.ml * dw - Jm * Lambda;
          } else {
            // Lambda = -(J v-) / (J M^-1 J^T), 2x2 inverse by hand
            const double det = M.ll * M.mm - M.ml * M.ml;
            const double iLL = M.mm / det, iLM = -M.ml / det, iMM = M.ll / det;
            const double JMJ = Jl * Jl * iLL + 2.0 * Jl * Jm * iLM + Jm * Jm * iMM;
            Lambda = -(Jm * u_end) / JMJ;
            dw = (iLL * Jl + iLM * Jm) * Lambda;
            du = (iLM * Jl + iMM * Jm) * Lambda;
          }
          const double loss = 0.5 * (M.ll * dw * dw + 2.0 * M.ml * dw * du + M.mm * du * du);
          const double W = Pd * u_end;
          u = u_end + du;
          xi = u / calc_on_rail(mast.rail, l, x).dY;
          br.entry_time_s = t;
          br.entry_impulse_Ns = std::abs(Lambda) / (3.0 * std::sin(mast.rail.beta_rad));
          br.entry_drive_impulse_Ns = Pd;
          br.entry_energy_loss_J = loss;
          r.energy_lost_J += loss;
          r.drive_work_impulses_J += W;
          break;
        }
        case PhaseEnd::lock: {
          // The latch stops the struts' radial motion: g(0) xi^2 is lost; y_m' is continuous.
          const double loss = 0.5 * p_end.mass_xx * p_end.qdot * p_end.qdot;
          br.lock_time_s = t;
          br.latch_energy_J = loss;
          r.energy_lost_J += loss;
          u = u_end;
          ke_end = p_end.kinetic_energy_J - loss;
          ++r.bays_completed;
          break;
        }
        case PhaseEnd::rail_exit: {
          // The lower frame lands on the stack: plastic, its velocity w -> 0.
          const TwoFrameMass M = calc_two_frame_mass(mast, s, p_end.y_lower_m, p_end.y_driven_m);
          const double w_end = p_end.w_m_per_s;
          const double dw = -w_end;
          double du, Pd = 0.0;
          if (kinematic) { du = 0.0; Pd = M.ml * dw; }
          else du = -M.ml * dw / M.mm;
          const double stack_impulse = M.ll * dw + M.ml * du;
          const double loss = 0.5 * (M.ll * dw * dw + 2.0 * M.ml * dw * du + M.mm * du * du);
          const double W = Pd * u_end;
          u = u_end + du;
          br.entry_time_s = t;
          br.landing_impulse_Ns = std::abs(stack_impulse);
          br.entry_impulse_Ns = 0.0;  // the pin leaves the rail: no rail impulse
          br.entry_drive_impulse_Ns = Pd;
          br.entry_energy_loss_J = loss;
          r.energy_lost_J += loss;
          r.drive_work_impulses_J += W;
          break;
        }
        case PhaseEnd::reach_height: {
          u = u_end;
          ++r.bays_completed;
          if (s.final_landing) {
            // Frame n lands on the stack: the whole (stowed) mast stops, plastic.
            r.energy_lost_J += p_end.kinetic_energy_J;
            ke_end = 0.0;
            u = 0.0;
          } else {
            ke_end = p_end.kinetic_energy_J;
          }
          break;
        }
      }
    }
    br.peak_drive_force_N = std::isfinite(tr.stage_force.value) ? tr.stage_force.value : kNaN;
    br.peak_drive_force_time_s = tr.stage_force.t;
    br.peak_pin_force_N = std::isfinite(tr.stage_pin.value) ? tr.stage_pin.value : kNaN;
    br.peak_pin_force_time_s = tr.stage_pin.t;
    tr.run[kForce].offer(tr.stage_force.value, tr.stage_force.t, tr.stage_force.bay);
    tr.run[kPin].offer(tr.stage_pin.value, tr.stage_pin.t, tr.stage_pin.bay);
  }
  if (failed) {
    // partial stage: its peaks so far still count
    tr.run[kForce].offer(tr.stage_force.value, tr.stage_force.t, tr.stage_force.bay);
    tr.run[kPin].offer(tr.stage_pin.value, tr.stage_pin.t, tr.stage_pin.bay);
    if (tr.bay > 0) {
      sim::BayResult& br = r.bays[static_cast<std::size_t>(tr.bay - 1)];
      if (std::isfinite(tr.stage_force.value)) { br.peak_drive_force_N = tr.stage_force.value; br.peak_drive_force_time_s = tr.stage_force.t; }
      if (std::isfinite(tr.stage_pin.value)) { br.peak_pin_force_N = tr.stage_pin.value; br.peak_pin_force_time_s = tr.stage_pin.t; }
    }
    ke_end = last.kinetic_energy_J;
  } else {
    r.deploy_time_s = t;
  }
  // The last row of a history is the end of the run (on the grid or not).
  if (hist.out && (r.history.t_s.empty() || r.history.t_s.back() < t)) hist.push(t, last, last_stage ? last_stage->bay : 0);

  auto fin = [](double v) { return std::isfinite(v) ? v : kNaN; };
  r.peak_drive_force_N = fin(tr.run[kForce].value);
  r.peak_drive_force_time_s = tr.run[kForce].t;
  r.peak_drive_force_bay = tr.run[kForce].bay;
  r.min_drive_force_N = fin(-tr.run[kNegForce].value);
  r.min_drive_force_time_s = tr.run[kNegForce].t;
  r.min_drive_force_bay = tr.run[kNegForce].bay;
  r.peak_drive_torque_Nm = drive.calc_torque_Nm(r.peak_drive_force_N);
  r.min_drive_torque_Nm = drive.calc_torque_Nm(r.min_drive_force_N);
  r.peak_pin_force_N = fin(tr.run[kPin].value);
  r.peak_pin_force_time_s = tr.run[kPin].t;
  r.peak_pin_force_bay = tr.run[kPin].bay;
  r.peak_diagonal_tension_N = fin(tr.run[kTension].value);
  for (const auto& b : r.bays)
    if (std::isfinite(b.latch_energy_J) && !(b.latch_energy_J <= r.peak_latch_energy_J)) r.peak_latch_energy_J = b.latch_energy_J;
  r.peak_driven_speed_m_per_s = fin(tr.run[kSpeed].value);
  r.max_rail_residual_m = tr.max_rail_residual;

  r.kinetic_energy_start_J = 0.0;
  r.kinetic_energy_end_J = ke_end;
  if (last_stage && last_phase) {
    if (failed) r.potential_energy_end_J = total_potential(*last_stage, *last_phase, last);
    else r.potential_energy_end_J = dir > 0 ? U_locked_suffix[1] : U_stowed_prefix[n];
  }
  r.drive_work_J = r.drive_work_smooth_J + r.drive_work_impulses_J;
  r.energy_residual_J = r.drive_work_J - (r.kinetic_energy_end_J - r.kinetic_energy_start_J) -
                        (r.potential_energy_end_J - r.potential_energy_start_J) - r.energy_lost_J;
  r.rhs_evals = evals;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return r;
}

}  // namespace truss::stages
