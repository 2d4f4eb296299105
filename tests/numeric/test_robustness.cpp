// Runs that never lie at the edges: stiff drives through the automatic integrator
// choice, degenerate rail geometry refused with its keys and range, solver failures named as such,
// the accuracy check on the energy balance, sane tolerances, bounded histories and the wall-time
// cap in closed form, and the creep stall of a time-stepped phase.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "integrators/auto_integrator.hpp"
#include "integrators/dop853.hpp"
#include "sim/simulate.hpp"
#include "stages/phase_dynamic.hpp"

using namespace truss;
using namespace truss::sim;
using Catch::Matchers::Contains;

namespace {

// y' = -k (y - cos t) - sin t, y(0) = 1: the solution is y = cos t for every k, and for k = 1e5 an
// explicit method is held to h < 3.3 / k by stability, not accuracy.
class StiffCosine : public integrators::OdeSystem {
 public:
  explicit StiffCosine(double k) : k_(k) {}
  int size() const override { return 1; }
  void calc_rhs(double t, const double* y, double* dy) override { dy[0] = -k_ * (y[0] - std::cos(t)) - std::sin(t); }

 private:
  double k_;
};

class Oscillator : public integrators::OdeSystem {
 public:
  int size() const override { return 2; }
  void calc_rhs(double, const double* y, double* dy) override { dy[0] = y[1]; dy[1] = -y[0]; }
};

SceneOptions table1(DriveMode mode, int n_bays = 30) {
  SceneOptions s;
  s.mast.n_bays = n_bays;
  s.drive.mode = mode;
  return s;
}

}  // namespace

TEST_CASE("auto integrator: a stiff problem goes to CVODE BDF, a non-stiff one stays on dopri54", "[robust][stiff]") {
  integrators::IntegratorOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  SECTION("stiff: k = 1e5") {
    StiffCosine sys(1e5);
    double y = 1.0;
    integrators::AutoIntegrator a(o);
    const auto s = a.integrate(sys, 0.0, 10.0, &y, nullptr);
    REQUIRE(s.status == integrators::IntegratorStatus::reached_end);
    CHECK(std::isfinite(a.get_switch_time_s()));
    CHECK(a.get_switch_time_s() < 1.0);
    // BDF's global error on the smooth solution, to rtol 1e-8 over 10 s: well inside 1e-6.
    CHECK(std::abs(y - std::cos(10.0)) < 1e-6);
    // dopri54 alone needs at least 10 / (3.3 / 1e5) = 3e5 steps; BDF needs a few thousand at most.
    CHECK(s.steps < 5000);
    // The explicit pair's own stiffness test fires on this problem.
    integrators::IntegratorOptions os = o;
    os.stop_when_stiff = true;
    integrators::DormandPrince54 dp(os);
    double y2 = 1.0;
    CHECK(dp.integrate(sys, 0.0, 10.0, &y2, nullptr).status == integrators::IntegratorStatus::stiff);
  }
  SECTION("non-stiff: the harmonic oscillator, bit for bit dopri54") {
    Oscillator sys;
    double ya[2] = {1.0, 0.0}, yb[2] = {1.0, 0.0};
    integrators::AutoIntegrator a(o);
    integrators::DormandPrince54 d(o);
    const auto sa = a.integrate(sys, 0.0, 50.0, ya, nullptr);
    const auto sb = d.integrate(sys, 0.0, 50.0, yb, nullptr);
    CHECK(std::isnan(a.get_switch_time_s()));
    CHECK(sa.steps == sb.steps);
    CHECK(ya[0] == yb[0]);
    CHECK(ya[1] == yb[1]);
  }
}

TEST_CASE("DOP853's stiffness test fires on a stiff problem, never on the oscillator", "[robust][stiff]") {
  // On StiffCosine two stages at the same time t + h differ by exactly -k times their states'
  // difference, so Hairer's estimate of h |lambda| is h k itself. DOP853's stability function has
  // |R(-x)| = 1 at x = 6.39 (R(z) = 1 + z b^T (I - z A)^-1 1 of its tableau): a step with h k above
  // its boundary 6.1 counts as stiff, and without the test the accepted steps cannot average h k
  // much above 6.39 (7 leaves room for the controller's excursions; an unstable step grows the
  // error and is rejected).
  integrators::IntegratorOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.stop_when_stiff = true;
  {
    StiffCosine sys(1e5);
    integrators::Dop853 dop(o);
    double y = 1.0;
    const auto s = dop.integrate(sys, 0.0, 10.0, &y, nullptr);
    INFO(s.to_string());
    REQUIRE(s.status == integrators::IntegratorStatus::stiff);
    // The test needs 15 steps with h k > 6.1; reaching t = 10 s at h k <= 6.39 would take over
    // 1.5e5 steps. It stops at an accepted state: on y = cos t to the tolerance.
    CHECK(s.steps >= 15);
    CHECK(s.steps < 1000);
    CHECK(s.t < 10.0);
    CHECK(std::abs(y - std::cos(s.t)) < 1e-6);
  }
  {
    integrators::IntegratorOptions free = o;
    free.stop_when_stiff = false;
    StiffCosine sys(1e5);
    integrators::Dop853 dop(free);
    double y = 1.0;
    const auto s = dop.integrate(sys, 0.0, 1.0, &y, nullptr);
    REQUIRE(s.status == integrators::IntegratorStatus::reached_end);
    CHECK(s.steps > 1e5 / 7.0);
    CHECK(std::abs(y - std::cos(1.0)) < 1e-6);
  }
  {
    // The oscillator is not stiff (|lambda| = 1, h < 1): the test never fires, and asking for it
    // changes nothing.
    integrators::IntegratorOptions off = o;
    off.stop_when_stiff = false;
    integrators::Dop853 a(o), b(off);
    Oscillator sys;
    double ya[2] = {1.0, 0.0}, yb[2] = {1.0, 0.0};
    const auto sa = a.integrate(sys, 0.0, 50.0, ya, nullptr);
    const auto sb = b.integrate(sys, 0.0, 50.0, yb, nullptr);
    CHECK(sa.status == integrators::IntegratorStatus::reached_end);
    CHECK(sa.steps == sb.steps);
    CHECK(ya[0] == yb[0]);
    CHECK(ya[1] == yb[1]);
  }
}

TEST_CASE("stiff drives end ok with the automatic choice", "[robust][stiff]") {
  // A strong motor on stiff diagonals (K = 1e4 N/m, stall torque 10 N m): dopri54 needs ~7e5 steps.
  SceneOptions s = table1(DriveMode::motor, 5);
  s.mast.diagonal_stiffness_N_per_m = 1e4;
  s.drive.stall_torque_Nm = 10.0;
  s.run.integrator = IntegratorKind::automatic;
  const RunResult a = simulate(s);
  REQUIRE(a.status == RunStatus::ok);
  CHECK(a.steps < 20000);
  // The same deployment by the explicit pair alone, to rtol 1e-10 (an independent method): the
  // lock times agree to the looser run's accuracy (rtol 1e-8 over ~17 s: 1e-6 s is generous).
  SceneOptions ref = s;
  ref.run.integrator = IntegratorKind::dopri54;
  ref.run.rtol = 1e-10;
  ref.run.atol = 1e-12;
  ref.run.max_steps = 20'000'000;
  const RunResult b = simulate(ref);
  REQUIRE(b.status == RunStatus::ok);
  CHECK(b.steps > 10 * a.steps);
  CHECK(std::abs(a.deploy_time_s - b.deploy_time_s) < 1e-6);
  for (int i = 0; i < 5; ++i) CHECK(std::abs(a.bays[i].lock_time_s - b.bays[i].lock_time_s) < 1e-6);
}

TEST_CASE("rail geometry at the held entry's limits is refused with the keys and the valid range", "[robust][rail]") {
  // Independent of model/rail.hpp: the held pin (hinge on the arc (l cos th, l sin th)) meets the
  // rail y = y_r - c x at least 1e-4 l_s from the straight bay iff the rail is above the arc's
  // point at cos th = d: l (c d + r) <= y_r, d = 1e-4, r = sqrt(1 - d^2); and the stowed pin (l, 0)
  // is clear of the rail iff y_r < c l. With y_r = y_l + c x_l that bounds x_l
  // (docs/model-notes.md, "Rail geometry").
  SceneOptions s = table1(DriveMode::velocity, 3);
  const double l = s.mast.strut_length_m, c = 1.0 / std::tan(s.rail.beta_deg * M_PI / 180.0), d = 1e-4;
  const double r = std::sqrt(1.0 - d * d);
  const double x_lo = (l * (c * d + r) - s.rail.y_m) / c, x_hi = (c * l - s.rail.y_m) / c;
  const std::string range = fmt::format("rail.x_m in [{:.9g}, {:.9g}) m", x_lo, x_hi);
  SECTION("just below the straight-bay limit") {
    s.rail.x_m = x_lo - 1e-9;
    const RunResult res = simulate(s);
    CHECK(res.status == RunStatus::invalid_input);
    CHECK_THAT(res.message, Contains(range) && Contains("straighten") && Contains("mast.strut_length_m"));
  }
  SECTION("inside the limits the run is ok, or flagged when its balance fails, never a silent lie") {
    for (double x : {x_lo + 5e-5, x_hi - 1e-7, x_hi - 1e-3}) {
      s.rail.x_m = x;
      s.mast.n_bays = 1;  // one stage: no later stage that starts past its entry (next section)
      const RunResult res = simulate(s);
      INFO(x << ": " << res.message);
      CHECK(res.status == RunStatus::ok);
    }
    s.mast.n_bays = 3;
    // 1e-7 m inside the straight-bay limit the struts whip in at ~500 m/s before the rail takes
    // them; the closed-form work integral cannot keep the balance there: flagged, not ok.
    s.rail.x_m = x_lo + 1e-7;
    const RunResult res = simulate(s);
    INFO(res.message);
    CHECK((res.status == RunStatus::ok || res.status == RunStatus::inaccurate));
    if (res.status == RunStatus::ok) CHECK(std::abs(res.energy_residual_J) < 1e-3 * std::abs(res.drive_work_J));
  }
  SECTION("a later stage starting past its entry: refused with the bound on rail.x_m") {
    // Frame 2 starts at y_r - l (bay 3's lock) and must be below the height y_r - c x_e + s_e at
    // which bay 2's pin meets the rail; at x_l = x_hi - 1e-7 it is not.
    s.rail.x_m = x_hi - 1e-7;
    const RunResult res = simulate(s);
    CHECK(res.status == RunStatus::invalid_input);
    CHECK_THAT(res.message, Contains("rail.x_m must be below"));
    // The bound it names is right: just below it the run is ok.
    const std::string& msg = res.message;
    const auto at = msg.find("must be below ") + 14;
    const double bound = std::stod(msg.substr(at));
    s.rail.x_m = bound * (1.0 - 1e-6);
    CHECK(simulate(s).status == RunStatus::ok);
    s.rail.x_m = bound * (1.0 + 1e-6);
    CHECK(simulate(s).status == RunStatus::invalid_input);
  }
  SECTION("the stowed pin not clear of the rail") {
    s.mast.n_bays = 1;
    s.rail.x_m = x_hi + 1e-9;
    const RunResult res = simulate(s);
    CHECK(res.status == RunStatus::invalid_input);
    CHECK_THAT(res.message, Contains(range) && Contains("not clear of the rail"));
  }
  SECTION("45 degrees and above: no rail.x_m works, and the message says why") {
    s.rail.beta_deg = 45.0 + 1e-9;
    const RunResult res = simulate(s);
    CHECK(res.status == RunStatus::invalid_input);
    CHECK_THAT(res.message, Contains("rail.beta_deg") && Contains("below 45 deg"));
  }
}

TEST_CASE("an integrator failure is a solver failure, distinct from the step cap", "[robust][status]") {
  // A 1 nm screw lead makes the motor line a damper of ~1e20 N s/m: the explicit pair's step
  // size underflows at the start.
  SceneOptions s = table1(DriveMode::motor, 3);
  s.drive.screw_lead_m = 1e-9;
  s.run.integrator = IntegratorKind::dopri54;
  const RunResult f = simulate(s);
  CHECK(f.status == RunStatus::solver_failure);
  CHECK_THAT(f.message, Contains("underflow"));
  SceneOptions capped = table1(DriveMode::motor, 3);
  capped.run.max_steps = 100;
  const RunResult c = simulate(capped);
  CHECK(c.status == RunStatus::step_limit);
  CHECK(c.steps <= 100 + 2 * 3);  // the cap holds to one step per phase (each phase gets >= 1)
}

TEST_CASE("the accuracy check: ok keeps its energy balance, a loose run is flagged", "[robust][accuracy]") {
  for (DriveMode m : {DriveMode::velocity, DriveMode::torque, DriveMode::motor})
    for (Direction dir : {Direction::deploy, Direction::retract}) {
      SceneOptions s = table1(m);
      s.run.direction = dir;
      const RunResult r = simulate(s);
      INFO(to_string(m) << " " << to_string(dir) << ": " << r.message);
      CHECK(r.status == RunStatus::ok);
    }
  // Torque retraction at rtol 1e-2: the residual is several per cent of the energy scale.
  SceneOptions loose = table1(DriveMode::torque);
  loose.run.direction = Direction::retract;
  loose.run.rtol = 1e-2;
  loose.run.atol = 1e-3;
  const RunResult r = simulate(loose);
  const double scale = std::abs(r.drive_work_smooth_J) + std::abs(r.drive_work_impulses_J) + r.energy_lost_J +
                       r.kinetic_energy_start_J + r.kinetic_energy_end_J + std::abs(r.potential_energy_start_J) +
                       std::abs(r.potential_energy_end_J);
  INFO("residual " << r.energy_residual_J << " J of " << scale << " J");
  REQUIRE(std::abs(r.energy_residual_J) > 0.01 * scale);
  CHECK(r.status == RunStatus::inaccurate);
  CHECK_THAT(r.message, Contains("energy residual") && Contains("rtol"));
  CHECK(std::isfinite(r.deploy_time_s));  // the run completed: its numbers are kept, not promised
}

TEST_CASE("tolerances outside the sane range are refused, naming the key", "[robust][tolerance]") {
  auto message = [](double rtol, double atol) {
    SceneOptions s = table1(DriveMode::torque, 2);
    s.run.rtol = rtol;
    s.run.atol = atol;
    return s.validate();
  };
  CHECK(message(1e-8, 1e-10).empty());
  CHECK_THAT(message(0.5, 1e-10), Contains("run.rtol"));
  CHECK_THAT(message(1e-16, 1e-10), Contains("run.rtol"));
  CHECK_THAT(message(1e-8, 1e9), Contains("run.atol"));
  CHECK_THAT(message(1e-8, 0.0), Contains("run.atol"));
}

namespace {
// The bytes a history holds: every column's capacity (what is allocated, not just what is used).
std::size_t held_bytes(const stages::TimeHistory& h) {
  std::size_t b = 4 * h.bay.capacity() + 8 * h.frame_height_m.capacity();
  for (const auto* v : {&h.t_s, &h.y_driven_m, &h.y_lower_m, &h.hinge_x_m, &h.hinge_y_m, &h.drive_force_N,
                        &h.drive_torque_Nm, &h.pin_force_N, &h.diagonal_tension_N, &h.driven_speed_m_per_s})
    b += 8 * v->capacity();
  return b;
}
}  // namespace

TEST_CASE("histories are bounded: at the byte cap the step doubles and the even grid rows stay", "[robust][history]") {
  SceneOptions s = table1(DriveMode::velocity, 3);
  s.run.output_step_s = 1e-3;
  const RunResult full = simulate(s);
  s.run.max_history_bytes = 50 * 84;  // 50 rows of 84 B (t, 9 columns, the bay)
  const RunResult cut = simulate(s);
  REQUIRE(full.status == RunStatus::ok);
  REQUIRE(cut.status == RunStatus::ok);
  CHECK(full.history.step_s == 1e-3);
  CHECK(cut.history.size() <= 50);
  CHECK(cut.history.size() >= 25);
  const double k = std::log2(cut.history.step_s / 1e-3);
  CHECK(k == std::round(k));
  CHECK(k >= 1.0);
  // Every row but the last (the end of the run) is the full history's row at the same time.
  const std::size_t stride = static_cast<std::size_t>(std::lround(cut.history.step_s / 1e-3));
  for (std::size_t i = 0; i + 1 < cut.history.size(); ++i) {
    INFO("row " << i);
    REQUIRE(i * stride < full.history.size());
    CHECK(cut.history.t_s[i] == full.history.t_s[i * stride]);
    CHECK(cut.history.drive_force_N[i] == full.history.drive_force_N[i * stride]);
  }
  CHECK(cut.history.t_s.back() == full.history.t_s.back());
  CHECK(cut.deploy_time_s == full.deploy_time_s);
  CHECK(held_bytes(cut.history) <= static_cast<std::size_t>(s.run.max_history_bytes));
}

// A free-stack row carries every frame's height: 8 (n + 1) B more. 300 bays at a 1 ms step would
// hold about 165 MB uncapped (66 s of motion); the cap holds whatever the row size.
TEST_CASE("free-stack histories are bounded in bytes, frame heights included", "[robust][history]") {
  SceneOptions s = table1(DriveMode::torque, 300);
  s.stack.mode = StackMode::free;
  s.mast.diagonal_free_length_m = 0.49;
  s.drive.torque_Nm = 0.002;
  s.run.output_step_s = 1e-3;
  s.run.max_history_bytes = 200'000;
  const RunResult r = simulate(s);
  INFO(r.message);
  CHECK(r.history.n_frames == 301);
  CHECK(r.history.size() >= 2);
  CHECK(held_bytes(r.history) <= 200'000u);
  CHECK(r.history.size() * (84 + 8 * 301) <= 200'000u);
  // below two rows of 84 + 8 * 301 B: refused before the run, naming the key
  s.run.max_history_bytes = 2 * (84 + 8 * 301) - 1;
  CHECK_THAT(s.validate(), Contains("run.max_history_bytes"));
}

TEST_CASE("the wall-time cap holds in velocity mode without a history (the clock read every few phases)",
          "[robust][caps]") {
  SceneOptions s = table1(DriveMode::velocity, 1000);
  s.run.output_step_s = 0.0;
  // The uncapped run's own wall time, the least of 5 (on a loaded machine one run can be
  // descheduled for many times its length, which would make a tenth of it no cap at all).
  double full_s = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 5; ++k) {
    const RunResult full = simulate(s);
    REQUIRE(full.status == RunStatus::ok);
    full_s = std::min(full_s, full.wall_time_s);
  }
  // a tenth of the uncapped run's own wall time: the cap must stop it well short of the last bay
  s.run.max_wall_time_s = 0.1 * full_s;
  const RunResult r = simulate(s);
  CHECK(r.status == RunStatus::wall_time_limit);
  CHECK(r.bays_completed < 1000);
}

TEST_CASE("the wall-time cap holds in velocity mode (closed form with a long history)", "[robust][caps]") {
  SceneOptions s = table1(DriveMode::velocity, 1000);
  s.drive.speed_m_per_s = 1e-3;
  s.run.output_step_s = 1e-3;
  s.run.max_wall_time_s = 0.01;  // uncapped, this run took 0.33 s and 1.4 M model evaluations (truss-sim --json, same keys)
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = simulate(s);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(r.status == RunStatus::wall_time_limit);
  CHECK(wall < 2.0);  // the cap plus one phase and the result's assembly, on a loaded machine
  CHECK(held_bytes(r.history) <= static_cast<std::size_t>(s.run.max_history_bytes));
}

namespace {
// q'' = -q': the speed decays as e^-t and never reaches zero; the end gap q - 10 is never reached
// from q(0) = 0, q'(0) = 1 (q -> 1).
class Decaying final : public stages::PhaseModel {
 public:
  Decaying() { ctx_.direction = 1.0; ctx_.drive.mode = model::DriveMode::torque; }
  int dof() const override { return 1; }
  const stages::PhaseContext& context() const override { return ctx_; }
  stages::PhasePoint calc_point(const double* q, const double* qdot, double* qddot, stages::PhaseScratch&) const override {
    qddot[0] = -qdot[0];
    stages::PhasePoint p;
    p.q = q[0]; p.qdot = qdot[0]; p.qddot = qddot[0]; p.u_m_per_s = qdot[0];
    return p;
  }
  double calc_driven_speed_m_per_s(const double*, const double* qdot) const override { return qdot[0]; }
  double calc_end_gap(const double* q) const override { return q[0] - 10.0; }
  double calc_end_gap_acceleration(const double*) const override { return 0.0; }
  void snap_to_end(double*) const override {}

 private:
  stages::PhaseContext ctx_;
};
}  // namespace

TEST_CASE("a time-stepped phase that creeps towards rest ends as a creep stall", "[robust][stall]") {
  Decaying model;
  integrators::IntegratorOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  integrators::DormandPrince54 integ(o);
  stages::PeakTracker peaks;
  stages::PhasePeaks phase_peaks;
  stages::TimeHistory h;
  model::DriveParams drive;
  stages::HistoryRecorder history(&h, 0.0, drive, 100);
  stages::PhaseSinks sinks{peaks, phase_peaks, history, std::chrono::steady_clock::now() + std::chrono::seconds(60)};
  const double q0 = 0.0, u0 = 1.0;
  const stages::PhaseOutcome out = stages::DynamicPhaseSolver(model, integ, o).solve({0.0, &q0, &u0, 1e-6}, sinks);
  CHECK(out.reason == stages::PhaseEndReason::crept_to_rest);
  // u = e^-t falls to 1e-6 at t = ln(1e6). The event time is located to 1e-13 s on the dense
  // output, but u itself carries the integration error, bounded by atol = 1e-12 against u = 1e-6
  // there: a relative error of ~1e-6 in u, i.e. ~1e-6 s in t. 1e-5 s leaves room for accumulation.
  CHECK(std::abs(out.t_end_s - std::log(1e6)) < 1e-5);
  // Without the creep speed the same phase runs on until its step budget (no stop, no end).
  o.max_steps = 2000;
  integrators::DormandPrince54 integ2(o);
  const stages::PhaseOutcome none = stages::DynamicPhaseSolver(model, integ2, o).solve({0.0, &q0, &u0, 0.0}, sinks);
  CHECK(none.reason != stages::PhaseEndReason::crept_to_rest);
}
