// Unit tests of the pieces of the stage loop: impact laws (model/impacts.hpp) against cases
// derived by hand (the numbers in the comments), the peak tracker and Hermite span against
// closed-form functions, and the energy ledger against a direct sum over the bays.
#include <catch2/catch.hpp>

#include <cmath>

#include "model/frames.hpp"
#include "model/impacts.hpp"
#include "stages/energy.hpp"
#include "stages/peaks.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {
// Exact up to a few roundings of O(1) numbers: 1e-14 relative.
constexpr double kRel = 1e-14;
}  // namespace

TEST_CASE("rail-entry impact: torque/motor drive, hand-derived", "[unit][impacts]") {
  // M = diag(2, 1), J = (1, 1), w = 0, u = 1: Lambda = -1 / (1/2 + 1) = -2/3,
  // dw = Lambda / 2 = -1/3, du = Lambda = -2/3; T: 1/2 -> 1/6, lost 1/3; no drive impulse.
  const model::TwoFrameMass M{2.0, 0.0, 1.0};
  const auto r = model::calc_rail_entry_impact(M, {1.0, 1.0}, 1.0, false);
  CHECK(r.rail_impulse_Ns == Approx(-2.0 / 3.0).epsilon(kRel));
  CHECK(r.dw_m_per_s == Approx(-1.0 / 3.0).epsilon(kRel));
  CHECK(r.du_m_per_s == Approx(-2.0 / 3.0).epsilon(kRel));
  CHECK(r.energy_loss_J == Approx(1.0 / 3.0).epsilon(kRel));
  CHECK(r.drive_impulse_Ns == 0.0);
  CHECK(r.drive_work_J == 0.0);
}

TEST_CASE("rail-entry impact: coupled mass matrix keeps the rail condition and loses energy", "[unit][impacts]") {
  // Any M > 0, J: after the impact J v+ = 0, and the loss equals T- - T+ (Carnot).
  const model::TwoFrameMass M{1.7, 0.4, 2.3};
  const Eigen::Vector2d J{0.9, -0.35};
  const double u = 0.13;
  const auto r = model::calc_rail_entry_impact(M, J, u, false);
  const Eigen::Vector2d vp{r.dw_m_per_s, u + r.du_m_per_s};
  CHECK(std::abs(J.dot(vp)) < 1e-15);
  const double T0 = 0.5 * M.mm * u * u;
  const double T1 = 0.5 * vp.dot(M.matrix() * vp);
  CHECK(r.energy_loss_J == Approx(T0 - T1).epsilon(1e-12));
  CHECK(r.energy_loss_J > 0.0);
}

TEST_CASE("rail-entry impact: velocity drive keeps u, hand-derived", "[unit][impacts]") {
  // M = diag(2, 1), J = (2, 1), u = 1 held: dw = -1 * 1 / 2 = -0.5, Lambda = 2 (-0.5) / 2 = -0.5,
  // P_d = 0 - 1 (-0.5) = 0.5, work 0.5, T: 1/2 -> 3/4, lost = W - dT = 0.25 = (1/2) 2 (-0.5)^2.
  const model::TwoFrameMass M{2.0, 0.0, 1.0};
  const auto r = model::calc_rail_entry_impact(M, {2.0, 1.0}, 1.0, true);
  CHECK(r.du_m_per_s == 0.0);
  CHECK(r.dw_m_per_s == Approx(-0.5).epsilon(kRel));
  CHECK(r.rail_impulse_Ns == Approx(-0.5).epsilon(kRel));
  CHECK(r.drive_impulse_Ns == Approx(0.5).epsilon(kRel));
  CHECK(r.drive_work_J == Approx(0.5).epsilon(kRel));
  CHECK(r.energy_loss_J == Approx(0.25).epsilon(kRel));
}

TEST_CASE("rail gradient is docs/model.md §3.1's corrected eq. 19 (correction 4)", "[unit][impacts]") {
  const double l = 0.18, D = 0.3, c = 1.0 / std::tan(20.85 * M_PI / 180.0);
  const double root = std::sqrt(4 * l * l - D * D), x = 0.5 * root;
  const Eigen::Vector2d J = model::calc_rail_gradient(c, D, x);
  CHECK(J[0] == Approx(0.5 + c * D / (2 * root)).epsilon(kRel));  // df/dy_{m-1}
  CHECK(J[1] == Approx(0.5 - c * D / (2 * root)).epsilon(kRel));  // df/dy_m
}

TEST_CASE("rail-exit landing, hand-derived", "[unit][impacts]") {
  // M = [[2, 0.5], [0.5, 1]], w = -0.3, u = -0.1.
  const model::TwoFrameMass M{2.0, 0.5, 1.0};
  SECTION("torque/motor: du = -0.5 * 0.3 / 1 = -0.15, stack 0.6 - 0.075, lost 0.07875") {
    const auto r = model::calc_rail_exit_impact(M, -0.3, -0.1, false);
    CHECK(r.dw_m_per_s == Approx(0.3).epsilon(kRel));
    CHECK(r.du_m_per_s == Approx(-0.15).epsilon(kRel));
    CHECK(r.stack_impulse_Ns == Approx(0.525).epsilon(kRel));
    CHECK(r.energy_loss_J == Approx(0.07875).epsilon(kRel));
    CHECK(r.drive_work_J == 0.0);
  }
  SECTION("velocity: du = 0, P_d = 0.15, stack 0.6, lost 0.09, work -0.015") {
    const auto r = model::calc_rail_exit_impact(M, -0.3, -0.1, true);
    CHECK(r.du_m_per_s == 0.0);
    CHECK(r.drive_impulse_Ns == Approx(0.15).epsilon(kRel));
    CHECK(r.stack_impulse_Ns == Approx(0.6).epsilon(kRel));
    CHECK(r.energy_loss_J == Approx(0.09).epsilon(kRel));
    CHECK(r.drive_work_J == Approx(-0.015).epsilon(kRel));
  }
}

TEST_CASE("unlock, hand-derived", "[unit][impacts]") {
  // M_yy = 3, M_xx = 0.5, c = 2, u = -0.1 (retracting).
  SECTION("torque/motor: Lambda = 0.1 / (1/3 + 8) = 0.012, du = 0.004, xi = 0.048, lost 6e-4") {
    const auto r = model::calc_unlock_impact(3.0, 0.5, 2.0, -0.1, false);
    CHECK(r.du_m_per_s == Approx(0.004).epsilon(kRel));
    CHECK(r.hinge_speed_m_per_s == Approx(0.048).epsilon(kRel));
    CHECK(r.energy_loss_J == Approx(6e-4).epsilon(1e-13));
    CHECK(std::abs((-0.1 + r.du_m_per_s) + 2.0 * r.hinge_speed_m_per_s) < 1e-16);  // on the rail after
    CHECK(r.rail_impulse_Ns == Approx(0.012).epsilon(kRel));
  }
  SECTION("velocity: xi = -u/c = 0.05, Lambda = 0.0125, work 1.25e-3, lost 6.25e-4") {
    const auto r = model::calc_unlock_impact(3.0, 0.5, 2.0, -0.1, true);
    CHECK(r.du_m_per_s == 0.0);
    CHECK(r.hinge_speed_m_per_s == Approx(0.05).epsilon(kRel));
    CHECK(r.drive_work_J == Approx(1.25e-3).epsilon(kRel));
    CHECK(r.rail_impulse_Ns == Approx(0.0125).epsilon(kRel));  // M_xx xi / c = 0.5 0.05 / 2
    CHECK(r.energy_loss_J == Approx(6.25e-4).epsilon(1e-13));
  }
}

TEST_CASE("latch loss and drive ramp, hand-derived", "[unit][impacts]") {
  CHECK(model::calc_latch_loss_J(0.5, 0.2) == Approx(0.01).epsilon(kRel));
  const auto ramp = model::calc_drive_ramp(1.8, 0.1);
  CHECK(ramp.impulse_Ns == Approx(0.18).epsilon(kRel));
  CHECK(ramp.work_J == Approx(0.009).epsilon(kRel));
}

TEST_CASE("peak tracker: bracketed grid maximum refined on the closed form", "[unit][peaks]") {
  // F(t) = 3 - (t - 0.37)^2 sampled at t = 0, 0.25, .., 1: the grid's best is t = 0.25 (2.9856);
  // refinement must find 3 at t = 0.37; the minimum of F on [0, 1] is at t = 1 (2.6031).
  auto point = [](double t) {
    stages::PhasePoint p;
    p.drive_force_N = 3.0 - (t - 0.37) * (t - 0.37);
    return p;
  };
  stages::PhasePeaks pp;
  pp.reset(1.0);
  for (int i = 0; i <= 4; ++i) pp.feed(0.25 * i, point(0.25 * i));
  stages::PeakTracker tr;
  tr.start_stage(7);
  tr.absorb(pp, [&](double t, const stages::HermiteSpan&) { return point(t); }, 1e-12);
  CHECK(tr.stage_force.value == Approx(3.0).epsilon(1e-14));
  CHECK(tr.stage_force.t == Approx(0.37).margin(1e-7));  // flat top: t to sqrt(eps)
  CHECK(tr.stage_force.bay == 7);
  CHECK(-tr.run[stages::kNegForce].value == Approx(3.0 - 0.63 * 0.63).epsilon(1e-14));
  CHECK(tr.run[stages::kNegForce].t == 1.0);
  tr.close_stage();
  CHECK(tr.run[stages::kForce].value == tr.stage_force.value);
  // A later equal value does not replace the earliest occurrence (docs/model.md §5).
  CHECK_FALSE(tr.run[stages::kForce].offer(tr.stage_force.value, 5.0, 1));
  CHECK(tr.run[stages::kForce].bay == 7);
}

TEST_CASE("peak ties: values within the tie tolerance of the largest are one peak, reported where it first occurs",
          "[unit][peaks]") {
  const double tol = 1e-6;
  stages::Extremum e;
  e.tie_tol = tol;
  CHECK(e.offer(1.0, 1.0, 5));
  e.offer(1.0 + 0.5 * tol, 2.0, 4);  // a tie: the first's time and bay stay, the value is the largest
  CHECK(e.t == 1.0);
  CHECK(e.bay == 5);
  CHECK(e.value == 1.0 + 0.5 * tol);
  CHECK(e.largest() == e.value);
  // 1 + 1.5 tol: the first is no longer within tol of the largest, the second is (by exactly tol).
  CHECK(e.offer(1.0 + 1.5 * tol, 3.0, 3));
  CHECK(e.t == 2.0);
  CHECK(e.bay == 4);
  CHECK(e.offer(1.0 + 4 * tol, 4.0, 2));  // clearly larger: it alone
  CHECK(e.t == 4.0);
  CHECK_FALSE(e.offer(0.5, 5.0, 1));      // smaller: nothing
  CHECK(e.t == 4.0);
  e.clear();
  CHECK(e.tie_tol == tol);
  CHECK(e.offer(-2.0, 6.0, 1));           // negative values: tol of the magnitude
  e.offer(-2.0 + tol, 7.0, 1);
  CHECK(e.t == 6.0);
  CHECK(e.value == -2.0 + tol);

  // Within a phase: two local maxima of the drive force within tol, the later one higher: the
  // earliest is reported (t = 0.3) with the larger value; beyond tol the later one alone.
  for (const double bump : {0.5 * tol, 3.0 * tol}) {
    auto point = [&](double t) {
      stages::PhasePoint p;
      p.drive_force_N = std::exp(-200.0 * (t - 0.3) * (t - 0.3)) + (1.0 + bump) * std::exp(-200.0 * (t - 0.7) * (t - 0.7));
      return p;
    };
    stages::PhasePeaks pp;
    pp.set_tie_tolerance(tol);
    pp.reset(1.0);
    for (int i = 0; i <= 40; ++i) pp.feed(0.025 * i, point(0.025 * i));
    stages::PeakTracker tr;
    tr.set_tie_tolerance(tol);
    tr.start_stage(1);
    tr.absorb(pp, [&](double t, const stages::HermiteSpan&) { return point(t); }, 1e-12);
    INFO("second maximum higher by " << bump);
    CHECK(tr.stage_force.t == Approx(bump < tol ? 0.3 : 0.7).margin(1e-4));
    CHECK(tr.stage_force.value == Approx(1.0 + bump).epsilon(1e-12));
  }
}

TEST_CASE("Hermite span interpolates quintic motion of any number of coordinates exactly", "[unit][peaks]") {
  // q_i(t) = a_i t^5 + b_i t^2 + c_i: quintic Hermite on (q, q', q'') at both ends is exact.
  const double a[3] = {0.3, -1.1, 2.0}, b[3] = {1.0, 0.5, -0.2}, c[3] = {0.1, 0.0, 4.0};
  auto state = [&](double t) {
    std::vector<double> s(9);
    for (int i = 0; i < 3; ++i) {
      s[i] = a[i] * std::pow(t, 5) + b[i] * t * t + c[i];
      s[3 + i] = 5 * a[i] * std::pow(t, 4) + 2 * b[i] * t;
      s[6 + i] = 20 * a[i] * std::pow(t, 3) + 2 * b[i];
    }
    return s;
  };
  stages::Sample sa, sb;
  const auto s0 = state(0.2), s1 = state(0.7);
  sa.assign(0.2, {}, s0.data(), 9);
  sb.assign(0.7, {}, s1.data(), 9);
  const stages::HermiteSpan span{&sa, &sb};
  REQUIRE(span.dof() == 3);
  double q[3], qd[3];
  span.calc(0.45, q, qd);
  const auto ref = state(0.45);
  for (int i = 0; i < 3; ++i) {
    CHECK(q[i] == Approx(ref[i]).epsilon(1e-13).margin(1e-14));
    CHECK(qd[i] == Approx(ref[3 + i]).epsilon(1e-12).margin(1e-13));
  }
}

TEST_CASE("energy ledger: stowed and locked potentials against a direct sum; the residual", "[unit][energy]") {
  model::MastParams mast;
  mast.bays.resize(3);
  mast.frames.resize(4);
  mast.bays[0].diagonal_free_length_m = 0.30;  // taut even stowed: b_f = 0.36 > 0.30
  mast.bays[1].diagonal_stiffness_N_per_m = 35.0;
  mast.frames[2].side_m = 0.4;
  const stages::EnergyLedger ledger(mast);
  const double stowed[4] = {0, 0, 0, 0};
  double deployed[4] = {0, 0, 0, 0};
  for (int i = 1; i <= 3; ++i) deployed[i] = deployed[i - 1] + 2.0 * mast.bay(i).strut_length_m;
  CHECK(ledger.get_stowed_potential_J() == Approx(model::calc_potential_energy_J(mast, stowed)).epsilon(1e-14));
  CHECK(ledger.get_stowed_potential_J() > 0.0);
  CHECK(ledger.get_deployed_potential_J() == Approx(model::calc_potential_energy_J(mast, deployed)).epsilon(1e-14));
  // Stage of bay 2 on the rail (frames 1, 2 moving): bay 3 locked above, nothing stowed below.
  double mixed[4] = {0, 0.1, 0.3, 0.66};
  const double b2 = model::calc_diagonal_offset_sq_m2(mast.frame(2), mast.frame(3));
  const double U3 = model::calc_bay_potential_J(mast.bay(3), b2, 0.36);
  const double moving = model::calc_potential_energy_J(mast, mixed) - U3;
  CHECK(ledger.calc_total_potential_J(2, 1, moving) == Approx(model::calc_potential_energy_J(mast, mixed)).epsilon(1e-14));
  stages::EnergyLedger l2(mast);
  l2.add_smooth_work(5.0);
  l2.add_impulse_work(0.5);
  l2.add_loss(0.25);
  l2.add_loss(0.25);
  l2.set_start(0.0, 1.0);
  l2.set_end(2.0, 3.5);
  stages::RunResult r;
  l2.fill(r);
  CHECK(r.drive_work_J == 5.5);
  CHECK(r.energy_lost_J == 0.5);
  CHECK(r.energy_residual_J == Approx(5.5 - 2.0 - 2.5 - 0.5).margin(1e-15));
}

#include <Eigen/Dense>

#include "model/tridiagonal.hpp"

TEST_CASE("tridiagonal and bordered solves agree with a dense LU of the same system", "[unit][tridiagonal]") {
  // An SPD tridiagonal matrix like the mast's (diagonally dominant), n = 7, and one border row.
  const int n = 7;
  Eigen::VectorXd diag(n), sub(n), a(n), r(n);
  for (int k = 0; k < n; ++k) {
    diag[k] = 3.0 + 0.3 * k;
    sub[k] = k > 0 ? -0.9 + 0.1 * k : 0.0;
    a[k] = k == n - 1 ? 0.35 : (k == n - 2 ? 0.65 : 0.0);  // the rail row touches frames m-1, m
    r[k] = std::sin(1.0 + k);
  }
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    M(k, k) = diag[k];
    if (k > 0) M(k, k - 1) = M(k - 1, k) = sub[k];
  }
  model::TridiagonalWork w;
  Eigen::VectorXd x;
  REQUIRE(model::solve_tridiagonal(diag, sub, r, x, w));
  const Eigen::VectorXd xd = M.partialPivLu().solve(r);
  CHECK((x - xd).norm() < 1e-14 * xd.norm());  // both backward stable on a well-conditioned M
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n + 1, n + 1);
  B.topLeftCorner(n, n) = M;
  B.block(0, n, n, 1) = a;
  B.block(n, 0, 1, n) = a.transpose();
  Eigen::VectorXd rb(n + 1);
  rb << r, 0.02;
  const Eigen::VectorXd xb = B.partialPivLu().solve(rb);
  double lambda = 0;
  REQUIRE(model::solve_bordered(diag, sub, a, r, 0.02, x, lambda, w));
  CHECK((x - xb.head(n)).norm() < 1e-13 * xb.norm());
  CHECK(lambda == Approx(xb[n]).epsilon(1e-12));
  CHECK(a.dot(x) == Approx(0.02).epsilon(1e-13));
  Eigen::VectorXd bad = diag;
  bad[3] = -1.0;
  CHECK_FALSE(model::solve_tridiagonal(bad, sub, r, x, w));
}

TEST_CASE("tail-constrained solve agrees with a dense LU of the bordered system, one and two rows", "[unit][tridiagonal]") {
  // M x = r + C mu, C' x = s with C's columns zero but on the last two rows (phase B's rail and
  // drive rows), against the dense (n + k) x (n + k) system [M -C; C' 0] [x; mu] = [r; s].
  for (int n : {2, 3, 7, 8, 9, 30, 31}) {  // below and from kTwistedRows
    Eigen::VectorXd diag(n), sub(n), r(n), cols[2] = {Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
    for (int k = 0; k < n; ++k) {
      diag[k] = 3.0 + 0.3 * k;
      sub[k] = k > 0 ? -0.9 + 0.1 * k : 0.0;
      r[k] = std::sin(1.0 + k);
    }
    cols[0][n - 2] = 1.0; cols[0][n - 1] = 0.37;   // rail gradient (.., 1, c - x/s)
    cols[1][n - 2] = 1.0; cols[1][n - 1] = -0.81;  // drive row (.., 1, -k)
    const double s[2] = {0.02, -0.3};
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
    for (int k = 0; k < n; ++k) {
      M(k, k) = diag[k];
      if (k > 0) M(k, k - 1) = M(k - 1, k) = sub[k];
    }
    for (int kc = 1; kc <= 2; ++kc) {
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n + kc, n + kc);
      Eigen::VectorXd rb(n + kc);
      B.topLeftCorner(n, n) = M;
      rb.head(n) = r;
      for (int j = 0; j < kc; ++j) {
        B.block(0, n + j, n, 1) = -cols[j];
        B.block(n + j, 0, 1, n) = cols[j].transpose();
        rb[n + j] = s[j];
      }
      const Eigen::VectorXd xb = B.partialPivLu().solve(rb);
      model::TridiagonalWork w;
      Eigen::VectorXd x;
      double mu[2] = {0.0, 0.0};
      REQUIRE(model::solve_tail_constrained(diag, sub, r, cols, kc, s, x, mu, w));
      // Both backward stable on a well-conditioned system: agreement to a few ulps of its size.
      CHECK((x - xb.head(n)).norm() < 1e-13 * xb.norm());
      for (int j = 0; j < kc; ++j) {
        CHECK(mu[j] == Approx(xb[n + j]).epsilon(1e-12));
        CHECK(cols[j].dot(x) == Approx(s[j]).epsilon(1e-12));
      }
    }
    Eigen::VectorXd bad = diag;
    bad[n - 1] = -1.0;
    Eigen::VectorXd x;
    double mu[2];
    model::TridiagonalWork w;
    CHECK_FALSE(model::solve_tail_constrained(bad, sub, r, cols, 2, s, x, mu, w));
  }
}

#include "sim/simulate.hpp"

TEST_CASE("velocity mode reports the scene's motor torque at the prescribed speed; other modes NaN", "[unit][drive]") {
  sim::SceneOptions s;
  s.mast.n_bays = 3;
  s.drive.speed_m_per_s = 0.05;
  s.drive.stall_torque_Nm = 0.03;
  s.drive.no_load_speed_rad_per_s = 60.0;
  s.drive.screw_lead_m = 0.008;
  const sim::RunResult r = sim::simulate(s);
  REQUIRE(r.status == sim::RunStatus::ok);
  // omega = 2 pi 0.05 / 0.008 = 39.2699 rad/s; 0.03 (1 - 39.2699 / 60) = 0.0103650 N m
  CHECK(r.motor_torque_at_speed_Nm == Approx(0.03 * (1.0 - 2.0 * M_PI * 0.05 / 0.008 / 60.0)).epsilon(1e-14));
  // The stall margin: the motor's torque at speed less the largest torque the drive needed.
  CHECK(r.motor_torque_margin_Nm == Approx(r.motor_torque_at_speed_Nm - r.peak_drive_torque_Nm).epsilon(1e-14));
  CHECK(r.motor_torque_margin_Nm > 0.0);  // 10.4 mN m available against a few mN m needed
  sim::SceneOptions weak = s;
  weak.drive.stall_torque_Nm = 1e-4;  // 0.035 mN m at speed: below the peak the run needs
  const sim::RunResult w = sim::simulate(weak);
  CHECK(w.motor_torque_margin_Nm < 0.0);
  CHECK(w.peak_drive_torque_Nm == Approx(r.peak_drive_torque_Nm).epsilon(1e-14));  // the motion is prescribed
  s.drive.mode = model::DriveMode::torque;
  CHECK(std::isnan(sim::simulate(s).motor_torque_at_speed_Nm));
  CHECK(std::isnan(sim::simulate(s).motor_torque_margin_Nm));
}
