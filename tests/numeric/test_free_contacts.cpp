// Stack contacts of the free stack (docs/model.md §2 "free"): the cluster reduction,
// contact forces and landing impact against dense constrained solves (Eigen, a second method);
// resting lower frames against the held stack and a contact force computed here from docs/model.md §3;
// the energy ledger with landings at tight tolerance; no overlap with contacts on.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "model/contacts.hpp"
#include "model/free_impacts.hpp"
#include "model/frames.hpp"
#include "numeric/dense_frames.hpp"
#include "sim/simulate.hpp"
#include "test_helpers.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {

// Bays 3 and 4 closed (frames 2, 3, 4 at one height): clusters {1}, {2,3,4}, {5}, {6}.
constexpr double kChainY[7] = {0.0, 0.05, 0.12, 0.12, 0.12, 0.31, 0.52};
constexpr double kChainW[7] = {0.0, 0.01, -0.02, -0.02, -0.02, 0.05, 0.1};
// F = r = velocity terms + springs, as frames.hpp builds them.
struct Chain : testing::SixMovingFrames {
  Eigen::VectorXd F = sys.velocity_terms + sys.spring_forces;
  Chain() : SixMovingFrames(kChainY, kChainW) {}
};
const std::vector<int> kStarts = {0, 1, 4, 5};  // local frames (frame - 1)

}  // namespace

TEST_CASE("contacts: cluster reduction is T' M T and T' r, and the contact forces are the KKT multipliers",
          "[numeric][free][contacts]") {
  const Chain c;
  const Eigen::MatrixXd M = c.dense();
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(6, 4);  // frame velocity = T * cluster velocity
  T(0, 0) = 1; T(1, 1) = T(2, 1) = T(3, 1) = 1; T(4, 2) = 1; T(5, 3) = 1;
  Eigen::VectorXd d, s, r;
  model::reduce_to_clusters(c.sys.diag, c.sys.sub, c.F, kStarts, d, s, r);
  const Eigen::MatrixXd Mc = T.transpose() * M * T;
  const Eigen::VectorXd rc = T.transpose() * c.F;
  for (int i = 0; i < 4; ++i) {
    CHECK(d[i] == Approx(Mc(i, i)).epsilon(1e-14));
    CHECK(r[i] == Approx(rc[i]).epsilon(1e-13).margin(1e-15));
    if (i > 0) CHECK(s[i] == Approx(Mc(i, i - 1)).epsilon(1e-14));
    for (int j = 0; j < i - 1; ++j) CHECK(Mc(i, j) == Approx(0.0).margin(1e-15));  // still tridiagonal
  }
  // Dense KKT with the closed contacts (bays 3, 4: frames 2-3 and 3-4, local 1-2, 2-3) as
  // bilateral constraints: [M -C'; C 0] (a, lambda) = (F, 0); lambda_j pushes frame j up.
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(2, 6);
  C(0, 2) = 1; C(0, 1) = -1;
  C(1, 3) = 1; C(1, 2) = -1;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(8, 8);
  K.topLeftCorner(6, 6) = M;
  K.topRightCorner(6, 2) = -C.transpose();
  K.bottomLeftCorner(2, 6) = C;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(8);
  rhs.head(6) = c.F;
  const Eigen::VectorXd sol = K.fullPivLu().solve(rhs);
  // The cluster solve expanded to frames gives the same accelerations ...
  Eigen::MatrixXd Md = Eigen::MatrixXd::Zero(4, 4);
  for (int i = 0; i < 4; ++i) { Md(i, i) = d[i]; if (i > 0) Md(i, i - 1) = Md(i - 1, i) = s[i]; }
  const Eigen::VectorXd a = T * Md.ldlt().solve(r);
  for (int k = 0; k < 6; ++k) CHECK(a[k] == Approx(sol[k]).epsilon(1e-10).margin(1e-12));
  // ... and the smallest contact force is the smaller multiplier, at its frame.
  int at = -1;
  const double lam = model::calc_min_cluster_contact_force_N(c.sys.diag, c.sys.sub, c.F, a, kStarts, at);
  const int want = sol[6] < sol[7] ? 2 : 3;
  CHECK(at == want);
  CHECK(lam == Approx(std::min(sol[6], sol[7])).epsilon(1e-9).margin(1e-12));
  CHECK(std::abs(sol[6] - sol[7]) > 1e-6);  // the two forces differ: the check locates the right one
}

TEST_CASE("contacts: landing impact with the screw holding its speed equals a dense KKT solve", "[numeric][free][contacts]") {
  const Chain c;
  const Eigen::MatrixXd M = c.dense();
  Eigen::VectorXd v(6);
  v << 0.01, -0.02, 0.03, 0.05, -0.04, 0.1;  // frame 5 falls onto frame 4 (local 4 onto 3)
  std::vector<Eigen::VectorXd> rows(2, Eigen::VectorXd::Zero(6));
  rows[0][4] = 1.0; rows[0][3] = -1.0;  // contact of bay 5: J v+ = 0
  rows[1][5] = 1.0;                     // the driven frame keeps its speed
  Eigen::Vector3d d(-(v[4] - v[3]), 0.0, 0.0);
  model::TridiagonalWork w;
  const model::ConstrainedImpact imp = model::calc_constrained_impact(c.sys.diag, c.sys.sub, rows, d, w);
  REQUIRE(imp.ok);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(8, 8);
  K.topLeftCorner(6, 6) = M;
  for (int j = 0; j < 2; ++j) { K.block(0, 6 + j, 6, 1) = -rows[j]; K.block(6 + j, 0, 1, 6) = rows[j].transpose(); }
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(8);
  rhs.head(6) = M * v;
  rhs[7] = v[5];
  const Eigen::VectorXd sol = K.fullPivLu().solve(rhs);  // (v+, Lambda, P_d)
  for (int k = 0; k < 6; ++k) CHECK(v[k] + imp.dv[k] == Approx(sol[k]).margin(1e-14));
  CHECK(imp.impulses[0] == Approx(sol[6]).epsilon(1e-10));
  CHECK(imp.impulses[0] > 0.0);  // a landing pushes: compressive
  CHECK(imp.impulses[1] == Approx(sol[7]).epsilon(1e-10));
  const Eigen::VectorXd vp = sol.head(6);
  // T+ - T- = P_d u - loss (Carnot: the contact impulse is workless on v+).
  CHECK(0.5 * vp.dot(M * vp) - 0.5 * v.dot(M * v) == Approx(imp.impulses[1] * v[5] - imp.energy_loss_J).epsilon(1e-10));
}

namespace {

sim::SceneOptions contact_scene(model::DriveMode mode) {
  sim::SceneOptions s;
  s.stack.mode = sim::StackMode::free;
  s.stack.contacts = sim::StackContacts::on;
  s.drive.mode = mode;
  return s;
}

// Contact force on a lower frame resting on the stack while the driven frame m moves (docs/model.md §3,
// written out here): lambda = (9/8 m_s - 2G) a_m - G'(D) (dD/dt)^2 - dU/dD, Table 1 values.
double calc_resting_force_N(double D, double u, double a) {
  const double ms = 0.1, l = 0.18, Jc = ms * l * l / 12.0, K = 20.0, l0 = 0.45, b = 0.36;
  const double den = 4.0 * l * l - D * D;
  const double G = (3.0 / 16.0 * ms * D * D + 3.0 * Jc) / den;
  const double dG = D * (1.5 * ms * l * l + 6.0 * Jc) / (den * den);
  const double L = std::sqrt(b * b + D * D);
  const double dU = L > l0 ? 6.0 * K * (L - l0) * D / L : 0.0;
  return (9.0 / 8.0 * ms - 2.0 * G) * a - dG * u * u - dU;
}

}  // namespace

TEST_CASE("contacts: resting lower frames follow the held stack until their contact force vanishes",
          "[numeric][free][contacts]") {
  // A free stack whose lower frames rest in closed contact IS the held stack as long as the
  // contacts push. The force that keeps frame m-1 resting is computed here from the held run's
  // motion; the free run must leave the held motion where that force falls through zero. For the
  // torque and motor drives this happens before rail entry (the struts' G'(D) (dD/dt)^2 grows
  // with D), so the held stack is reproduced up to the lift-off, not up to entry (model-notes).
  for (const auto mode : {model::DriveMode::torque, model::DriveMode::motor}) {
    INFO((mode == model::DriveMode::torque ? "torque" : "motor"));
    sim::SceneOptions s = contact_scene(mode);
    s.mast.n_bays = 3;
    s.run.rtol = 1e-10;
    s.run.atol = 1e-12;
    s.run.output_step_s = 1e-4;
    const sim::RunResult fr = sim::simulate(s);
    s.stack.mode = sim::StackMode::held;
    s.stack.contacts = sim::StackContacts::off;
    const sim::RunResult held = sim::simulate(s);
    REQUIRE(held.status == sim::RunStatus::ok);
    const auto &hf = fr.history, &hh = held.history;
    const double h = 1e-4;
    // Predicted lift-off: the first sign change of the force on the held motion (central
    // differences for a_m, error O(h^2 u''') ~ 1e-9 m/s^2, far below the force's slope).
    double t_pred = -1;
    for (std::size_t k = 1; k + 1 < hh.size() && hh.bay[k + 1] == 3; ++k) {
      const double a = (hh.driven_speed_m_per_s[k + 1] - hh.driven_speed_m_per_s[k - 1]) / (2 * h);
      if (calc_resting_force_N(hh.y_driven_m[k], hh.driven_speed_m_per_s[k], a) < 0.0) { t_pred = hh.t_s[k]; break; }
    }
    REQUIRE(t_pred > 0.0);
    REQUIRE(t_pred < held.bays[2].entry_time_s);  // before entry: the weaker check is the one that holds
    // Free run: frame 2 exactly at 0 while resting; the last resting sample brackets the lift-off.
    std::size_t k = 0;
    while (k + 1 < hf.size() && hf.y_lower_m[k + 1] == 0.0) ++k;
    CHECK(hf.t_s[k] <= t_pred + h);
    CHECK(hf.t_s[k] >= t_pred - 2 * h);
    // Up to there the driven frame moves exactly as in the held stack (both at rtol 1e-10).
    for (std::size_t i = 0; i <= k; ++i) CHECK(hf.y_driven_m[i] == Approx(hh.y_driven_m[i]).margin(1e-9));
    CHECK(fr.contact_lift_offs >= 1);
  }
  SECTION("velocity drive: a_m = 0, the force is -G' v^2 <= 0 and the lower frame leaves at once") {
    sim::SceneOptions s = contact_scene(model::DriveMode::velocity);
    s.mast.n_bays = 3;
    s.run.output_step_s = 1e-3;
    const sim::RunResult fr = sim::simulate(s);
    REQUIRE(fr.history.size() > 2);
    CHECK(fr.history.y_lower_m[0] == 0.0);
    CHECK(fr.history.y_lower_m[1] > 0.0);  // at t = 1 ms already off the stack
  }
}

TEST_CASE("contacts: energy ledger with landings closes at tight tolerance in every drive mode", "[numeric][free][contacts]") {
  // W - dT - dU - E_lost with the landings' losses counted. Scenes with taut diagonals
  // (l_0 = 0.40 m) whose lower frames fall back onto the stack: the landings lose 1e-4 .. 0.2 of
  // the work, so a ledger without them misses by far more than 1e-9 of the work; the integration
  // error at rtol 1e-12 is ~1e-10 of it (measured <= 1.3e-10).
  struct Case { model::DriveMode mode; double K, v, stall; bool landings; };
  for (const Case c : {Case{model::DriveMode::velocity, 100.0, 0.1, 0.02, true}, Case{model::DriveMode::motor, 20.0, 0.1, 0.02, true},
                       Case{model::DriveMode::torque, 20.0, 0.1, 0.02, false}}) {
    sim::SceneOptions s = contact_scene(c.mode);
    s.mast.n_bays = 8;
    s.mast.diagonal_free_length_m = c.landings ? 0.40 : 0.50;
    s.mast.diagonal_stiffness_N_per_m = c.K;
    s.drive.speed_m_per_s = c.v;
    s.drive.torque_Nm = 0.002;
    s.drive.stall_torque_Nm = c.stall;
    s.run.rtol = 1e-12;
    s.run.atol = 1e-14;
    const sim::RunResult r = sim::simulate(s);
    INFO(r.message);
    REQUIRE(r.drive_work_J > 0.0);
    CHECK(std::isfinite(r.energy_residual_J));
    CHECK(std::abs(r.energy_residual_J) < 1e-9 * r.drive_work_J);
    CHECK(r.contact_lift_offs > 0);
    if (c.landings) {
      CHECK(r.contact_landings > 0);
      CHECK(r.contact_energy_loss_J > 1e-5 * r.drive_work_J);  // not vacuous
    } else {
      CHECK(r.status == sim::RunStatus::ok);
      CHECK(r.bays_completed == 8);
    }
    CHECK(r.min_bay_opening_m > -2e-9 * 0.18);  // no overlap beyond the landing tolerance (1e-9 l_s, located to ~1e-13 s)
  }
}

// ---- Free-stack retraction (docs/model.md §2: the reverse of deployment) ----

namespace {
sim::RunResult run_mode(sim::SceneOptions s, model::DriveMode mode) {
  s.drive.mode = mode;
  s.drive.torque_Nm = 0.002;
  return sim::simulate(s);
}
// Linear interpolation of a history column at time t (the rows are on a grid of step h).
double at(const std::vector<double>& t, const std::vector<double>& v, double tt) {
  std::size_t k = 1;
  while (k + 1 < t.size() && t[k] < tt) ++k;
  const double w = (tt - t[k - 1]) / (t[k] - t[k - 1]);
  return (1 - w) * v[k - 1] + w * v[k];
}
}  // namespace

TEST_CASE("free retraction: a one-bay free stack retracts as the held stack (other coordinates and laws)", "[numeric][free][retract]") {
  // Frame 0 is the only frame below the driven one: the free path (time-stepped bordered system,
  // n-frame unlock and exit impacts) must give the held path's numbers (closed form in velocity
  // mode, two-frame impact laws).
  for (const auto mode : {model::DriveMode::velocity, model::DriveMode::torque, model::DriveMode::motor}) {
    sim::SceneOptions s;
    s.mast.n_bays = 1;
    s.run.direction = model::Direction::retract;
    s.run.rtol = 1e-11;
    s.run.atol = 1e-13;
    const sim::RunResult held = run_mode(s, mode);
    s.stack.mode = sim::StackMode::free;
    const sim::RunResult fr = run_mode(s, mode);
    INFO(fr.message);
    REQUIRE(held.status == sim::RunStatus::ok);
    REQUIRE(fr.status == sim::RunStatus::ok);
    const auto &bh = held.bays[0], &bf = fr.bays[0];
    // As for the deployment: event times to ~1e-9 s after ~1e3 steps at rtol 1e-11.
    CHECK(bf.entry_time_s == Approx(bh.entry_time_s).epsilon(1e-8));
    CHECK(fr.end_time_s == Approx(held.end_time_s).epsilon(1e-8));
    CHECK(bf.latch_energy_J == Approx(bh.latch_energy_J).epsilon(1e-7).margin(1e-15));
    CHECK(bf.entry_energy_loss_J == Approx(bh.entry_energy_loss_J).epsilon(1e-7));
    CHECK(bf.landing_impulse_Ns == Approx(bh.landing_impulse_Ns).epsilon(1e-7));
    // the rail's impulse at the unlock: the n-frame impulse solve against the two-frame law
    REQUIRE(std::isfinite(bh.unlock_impulse_Ns));
    CHECK(bf.unlock_impulse_Ns == Approx(bh.unlock_impulse_Ns).epsilon(1e-9));
    CHECK(fr.drive_work_J == Approx(held.drive_work_J).epsilon(1e-7));
    CHECK(fr.energy_lost_J == Approx(held.energy_lost_J).epsilon(1e-7));
    CHECK(fr.peak_drive_force_N == Approx(held.peak_drive_force_N).epsilon(1e-6));
  }
}

TEST_CASE("free retraction in velocity mode is the time reverse of the deployment (one bay)", "[numeric][free][retract]") {
  // docs/model.md §2: retraction is the exact time reverse. With the driven frame prescribed, the motion
  // is kinematic: y_m(t) and the hinge path of the retraction are the deployment's at T - t.
  // Compared through linear interpolation of 1 ms histories (error h^2 |x''| / 8 < 1e-6 m) away
  // from the rail entry / exit, where the velocities jump.
  sim::SceneOptions s;
  s.mast.n_bays = 1;
  s.stack.mode = sim::StackMode::free;
  s.run.output_step_s = 1e-3;
  s.run.rtol = 1e-11;
  s.run.atol = 1e-13;
  const sim::RunResult dep = sim::simulate(s);
  s.run.direction = model::Direction::retract;
  const sim::RunResult ret = sim::simulate(s);
  REQUIRE(dep.status == sim::RunStatus::ok);
  REQUIRE(ret.status == sim::RunStatus::ok);
  const double T = dep.end_time_s;
  CHECK(ret.end_time_s == Approx(T).epsilon(1e-9));
  CHECK(ret.bays[0].entry_time_s == Approx(T - dep.bays[0].entry_time_s).epsilon(1e-8));  // rail exit mirrors entry
  const auto &hd = dep.history, &hr = ret.history;
  for (std::size_t k = 1; k + 1 < hr.size(); k += 17) {
    const double t = hr.t_s[k];
    // Not across the entry/exit kink (the velocities jump there: linear interpolation is O(h dv)).
    if (std::abs(t - ret.bays[0].entry_time_s) < 2e-3) continue;
    CHECK(hr.y_driven_m[k] == Approx(at(hd.t_s, hd.y_driven_m, T - t)).margin(1e-6));
    CHECK(hr.hinge_x_m[k] == Approx(at(hd.t_s, hd.hinge_x_m, T - t)).margin(1e-6));
    CHECK(hr.y_lower_m[k] == Approx(at(hd.t_s, hd.y_lower_m, T - t)).margin(1e-6));
    CHECK(hr.driven_speed_m_per_s[k] == Approx(-at(hd.t_s, hd.driven_speed_m_per_s, T - t)).margin(1e-9));
  }
}

TEST_CASE("free retraction: energy ledger at tight tolerance, contacts on and off, every drive mode", "[numeric][free][retract]") {
  // Contacts on: the rail pushes each lower frame back onto the stack, frames bounce (landings
  // and lift-offs), the final landing stops the stack. Contacts off: the paper's literal model.
  // W - dT - dU - E_lost within 1e-8 of the energy scale at rtol 1e-12 (measured <= 2e-10).
  for (const bool contacts : {true, false}) {
    for (const auto mode : {model::DriveMode::velocity, model::DriveMode::torque, model::DriveMode::motor}) {
      sim::SceneOptions s;
      s.mast.n_bays = 4;
      s.stack.mode = sim::StackMode::free;
      s.stack.contacts = contacts ? sim::StackContacts::on : sim::StackContacts::off;
      s.run.direction = model::Direction::retract;
      s.run.rtol = 1e-12;
      s.run.atol = 1e-14;
      const sim::RunResult r = run_mode(s, mode);
      INFO((contacts ? "contacts " : "no contacts ") << static_cast<int>(mode) << ": " << r.message);
      REQUIRE(r.status == sim::RunStatus::ok);
      CHECK(r.bays_completed == 4);
      const double scale = std::abs(r.drive_work_J) + r.energy_lost_J + std::abs(r.potential_energy_start_J - r.potential_energy_end_J);
      CHECK(r.energy_lost_J > 1e-3 * scale);  // impacts matter: not vacuous
      CHECK(std::abs(r.energy_residual_J) < 1e-8 * scale);
      // Every bay unlocks: a moving mast with a rail impulse; the first from rest (none in torque
      // and motor modes, where the drive starts the mast through the rail without an impact).
      for (const auto& b : r.bays) {
        INFO("bay " << b.bay);
        REQUIRE(std::isfinite(b.unlock_impulse_Ns));
        if (b.bay > 1 || mode == model::DriveMode::velocity) CHECK(b.unlock_impulse_Ns > 0);
        else CHECK(b.unlock_impulse_Ns == 0);
      }
      if (contacts) {
        CHECK(r.contact_landings > 0);
        CHECK(r.min_bay_opening_m > -2e-9 * 0.18);  // never through each other
      } else {
        CHECK(r.contact_landings == 0);
      }
    }
  }
}

TEST_CASE("with contacts on, an overlap deeper than locating a contact leaves is never ok", "[numeric][free][contacts]") {
  // A fuzz-found motor retraction at a loose rtol: dopri54 stepped over a landing and bay 10's
  // frames passed through each other by 7.9 mm (4.4 % of l_s), and the run was reported ok. The
  // bound is independent of this run: the located contacts of every ok run of this scene, at rtol
  // 1e-3 to 1e-12 and with all three integrators, overlap by 1.8e-10 m = 1e-9 l_s.
  sim::SceneOptions s;
  s.stack.mode = sim::StackMode::free;
  s.stack.contacts = sim::StackContacts::on;
  s.drive.mode = model::DriveMode::motor;
  s.run.direction = model::Direction::retract;
  s.mast.strut_mass_kg = 1.747890472863656e-06;
  s.mast.diagonal_free_length_m = 0.25008714633552476;
  s.rail.x_m = 0.10873884565261716;
  s.rail.y_m = 0.08219913449237358;
  s.rail.beta_deg = 40.81169048733838;
  s.run.rtol = 7.770454998915085e-05;
  s.run.integrator = integrators::IntegratorKind::dopri54;
  const sim::RunResult r = sim::simulate(s);
  INFO(r.message);
  CHECK(r.min_bay_opening_m < -1e-3);  // the crossing is still missed at this tolerance...
  CHECK(r.status == sim::RunStatus::inaccurate);  // ...and the run says so
  CHECK_THAT(r.message, Catch::Matchers::Contains("overlapped"));
  s.run.rtol = 1e-8;  // tight enough: every landing located, the run ok, the overlap within the bound
  const sim::RunResult t = sim::simulate(s);
  INFO(t.message);
  CHECK(t.status == sim::RunStatus::ok);
  CHECK(t.min_bay_opening_m >= -2e-9 * 0.18);  // the bound docs/model-notes.md states
}
