// The drive train and the motorisation check (model/drive.hpp, model/motorisation.hpp;
// docs/model-notes.md "Drive train", "Motorisation check"), against values derived here by hand:
// the lead screw's raise and lower laws with a gear in front, written out in long double, and the
// 12-bay held stack's required torque from the model's equations (docs/model.md §1, §3), not from
// the code: the pin meets the rail where the hinge of a bay opening from a held lower frame reaches
// the rail line, and there the constant-speed drive force is G'(D) v^2 + dU/dD (§3), its largest.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "model/drive.hpp"
#include "model/motorisation.hpp"
#include "sim/simulate.hpp"
#include "stages/phase_dynamic.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {

using ld = long double;
constexpr ld kPi = 3.141592653589793238462643383279502884L;

// A train with every term declared (N m at the motor shaft).
model::DriveParams make_train() {
  model::DriveParams d;
  d.gear_ratio = 4.0;
  d.gear_efficiency = 0.9;
  d.screw_efficiency = 0.4;
  d.screw_back_efficiency = 0.25;
  d.friction_torque_Nm = 1.0e-3;
  d.detent_torque_Nm = 2.0e-4;
  d.hysteresis_torque_Nm = 1.0e-4;
  d.harness_torque_Nm = 3.0e-4;
  d.motor_derating = 0.8;
  return d;
}

// Lead screw of lead h driven through a gear of ratio N (motor turns per screw turn): the motor's
// net torque T (after the losses) gives the axial force 2 pi N eta_g eta_s T / h when it drives the
// load (raise: T_screw = F h / (2 pi eta_s)) and 2 pi N T / (h eta_g eta_s') when the load drives it
// (lower: T_screw = F h eta_s' / (2 pi)). Along the run direction.
ld hand_force_along(const model::DriveParams& d, ld net_torque) {
  const ld ratio = 2 * kPi * d.gear_ratio / d.screw_lead_m;
  return net_torque >= 0 ? ratio * d.gear_efficiency * d.screw_efficiency * net_torque
                         : ratio * net_torque / (static_cast<ld>(d.gear_efficiency) * d.screw_back_efficiency);
}
ld hand_losses(const model::DriveParams& d) {
  return static_cast<ld>(d.friction_torque_Nm) + d.detent_torque_Nm + d.hysteresis_torque_Nm + d.harness_torque_Nm;
}

}  // namespace

TEST_CASE("drive train: an ideal train gives the ideal screw's force to the bit", "[unit][drive]") {
  // The products an ideal screw computes: F = d (2 pi / h) M (1 - omega / omega_0), F = d (2 pi / h) M_d.
  model::DriveParams d;
  d.mode = model::DriveMode::motor;
  for (const double dir : {1.0, -1.0})
    for (const double u : {0.0, 0.013, -0.021, 0.2}) {
      const double to_force = 2.0 * M_PI / d.screw_lead_m, omega = to_force * dir * u;
      CHECK(d.calc_force_N(u, dir) == dir * to_force * d.stall_torque_Nm * (1.0 - omega / d.no_load_speed_rad_per_s));
    }
  d.mode = model::DriveMode::torque;
  CHECK(d.calc_force_N(0.05, -1.0) == -1.0 * (2.0 * M_PI / d.screw_lead_m) * d.torque_Nm);
  CHECK(d.calc_motor_torque_for_force_Nm(3.1) == d.calc_torque_Nm(3.1));
  CHECK(d.calc_motor_torque_Nm(0.1) == d.stall_torque_Nm * (1.0 - 2.0 * M_PI / d.screw_lead_m * 0.1 / d.no_load_speed_rad_per_s));
}

TEST_CASE("drive train: the motor's force driving and backdriven, both directions, hand-derived", "[unit][drive]") {
  model::DriveParams d = make_train();
  d.mode = model::DriveMode::motor;
  const ld losses = hand_losses(d);  // 1.6 mN m
  for (const double dir : {1.0, -1.0}) {
    // Slow (the motor drives the load) and near its no-load speed (its torque below the losses: the
    // load drives the motor). Motor speed N 2 pi u / h along the run direction.
    for (const double speed : {0.004, 0.0297}) {
      const double u = dir * speed;
      const ld omega_m = d.gear_ratio * 2 * kPi * speed / d.screw_lead_m;
      const ld motor = static_cast<ld>(d.motor_derating) * d.stall_torque_Nm * (1 - omega_m / d.no_load_speed_rad_per_s);
      const ld along = hand_force_along(d, motor - losses);
      INFO("direction " << dir << ", speed " << speed << " m/s, net torque " << static_cast<double>(motor - losses));
      CHECK(d.calc_force_N(u, dir) == Approx(static_cast<double>(dir * along)).epsilon(1e-14));
      // The inverse: the torque the motor must give for that force is its own torque.
      CHECK(d.calc_motor_torque_for_force_Nm(static_cast<double>(along)) == Approx(static_cast<double>(motor)).epsilon(1e-13));
    }
  }
  // Both regimes are exercised: 0.004 m/s drives (net > 0), 0.0297 m/s is backdriven (net < 0).
  const auto net_at = [&](double speed) {
    return d.motor_derating * d.stall_torque_Nm * (1.0 - d.gear_ratio * 2.0 * M_PI * speed / d.screw_lead_m / d.no_load_speed_rad_per_s) -
           static_cast<double>(losses);
  };
  CHECK(net_at(0.004) > 0.0);
  CHECK(net_at(0.0297) < 0.0);
  // Torque mode: the constant torque through the same train (and no derating: the torque is given).
  d.mode = model::DriveMode::torque;
  d.torque_Nm = 0.0012;  // below the losses: the train brakes along the run direction
  CHECK(d.calc_force_N(0.01, -1.0) == Approx(static_cast<double>(-hand_force_along(d, 0.0012L - losses))).epsilon(1e-14));
  CHECK(d.calc_force_N(0.01, -1.0) > 0.0);  // retracting, the braking force points up
}

TEST_CASE("drive train: a motor behind a gear creeps relative to the screws' no-load speed", "[unit][drive]") {
  // The creep rule (docs/model-notes.md "Stall"): 1e-6 of the no-load screw speed, the motor's
  // omega_0 / N turned into the driven frame's speed omega h / (2 pi).
  model::DriveParams d = make_train();
  CHECK(stages::DynamicPhaseSolver::calc_creep_speed_m_per_s(d) ==
        Approx(1e-6 * (75.0 / 4.0) * 0.01 / (2.0 * M_PI)).epsilon(1e-15));
}

TEST_CASE("drive train: the 12-bay held stack's required torque and ECSS margin, derived by hand", "[unit][drive]") {
  sim::SceneOptions s;  // Table 1, velocity drive at 0.1 m/s, held stack
  s.mast.n_bays = 12;
  s.run.output_step_s = 0.0;
  s.drive.gear_ratio = 3.0;
  s.drive.gear_efficiency = 0.92;
  s.drive.screw_efficiency = 0.45;
  s.drive.screw_back_efficiency = 0.3;
  s.drive.friction_torque_Nm = 4.0e-4;
  s.drive.detent_torque_Nm = 1.5e-4;
  s.drive.hysteresis_torque_Nm = 0.5e-4;
  s.drive.harness_torque_Nm = 2.5e-4;
  s.drive.motor_derating = 0.85;
  s.drive.stall_torque_Nm = 0.02;
  s.drive.no_load_speed_rad_per_s = 600.0;  // 188.5 rad/s at the motor for 0.1 m/s
  const sim::RunResult r = sim::simulate(s);
  REQUIRE(r.status == sim::RunStatus::ok);

  // By hand (docs/model.md §1, §3), long double. Every stage opens its bay from the held lower
  // frame at y = 0: the hinge is at (sqrt(l^2 - D^2 / 4), D / 2) and meets the rail line
  // y - y_l + cot(beta) (x - x_l) = 0 at the opening D_e (Newton's method from the fold).
  const ld l = 0.18L, yl = 0.15L, xl = 0.08L, cb = 1 / std::tan(20.85L * kPi / 180);
  auto rail = [&](ld D) { return D / 2 - yl + cb * (std::sqrt(l * l - D * D / 4) - xl); };
  auto rail_dD = [&](ld D) { return 0.5L - cb * D / (4 * std::sqrt(l * l - D * D / 4)); };
  ld De = 0.3L;
  for (int i = 0; i < 60; ++i) De -= rail(De) / rail_dD(De);
  CHECK(static_cast<double>(De) == Approx(0.327473474).margin(5e-10));  // model.md §2's Y_e
  // Spring: U = 3 K (L - l_0)^2, L = sqrt(b_f^2 + D^2), dU/dD = 6 K (L - l_0) D / L. Inertial, at
  // constant speed v of the driven frame over the held lower frame: the Lagrangian's velocity term
  // G'(D) D'^2, G' = D (3/2 m_s l^2 + 6 J_c) / (4 l^2 - D^2)^2, J_c = m_s l^2 / 12.
  const ld K = 20, l0 = 0.45L, bf = 0.36L, ms = 0.1L, Jc = ms * l * l / 12, v = 0.1L, h = 0.01L;
  const ld L = std::sqrt(bf * bf + De * De);
  const ld spring_N = 6 * K * (L - l0) * De / L;
  const ld inertial_N = De * (1.5L * ms * l * l + 6 * Jc) / ((4 * l * l - De * De) * (4 * l * l - De * De)) * v * v;
  const ld to_torque = h / (2 * kPi);  // screw torque of a force
  const ld S = spring_N * to_torque, TD = inertial_N * to_torque;
  CHECK(r.peak_static_drive_torque_Nm == Approx(static_cast<double>(S)).epsilon(1e-9));
  CHECK(r.peak_inertial_drive_torque_Nm == Approx(static_cast<double>(TD)).epsilon(1e-9));
  // The motor drives the load: the torque at the motor is the losses plus the screw torque over
  // N eta_g eta_s.
  const ld N = 3, eta = 0.92L * 0.45L, losses = 4.0e-4L + 1.5e-4L + 0.5e-4L + 2.5e-4L;
  const ld needed = losses + (S + TD) / (N * eta);
  CHECK(r.peak_motor_torque_Nm == Approx(static_cast<double>(needed)).epsilon(1e-9));
  // ECSS-E-ST-33-01C 4.7.5.3.1 with Table 4-2's theoretical factors: MF 2 on 1.2 S + 3 F_R +
  // 1.5 H_M + 3 H_Y + 3 H_A, and 1.25 T_D (the prescribed speed is the acceleration requirement).
  const ld t_min = 2 * (1.2L * S / (N * eta) + 3 * 4.0e-4L + 1.5L * 1.5e-4L + 3 * 0.5e-4L + 3 * 2.5e-4L) + 1.25L * TD / (N * eta);
  const ld available = 0.85L * 0.02L * (1 - N * 2 * kPi * v / h / 600);
  CHECK(r.motorisation_required_torque_Nm == Approx(static_cast<double>(t_min)).epsilon(1e-9));
  CHECK(r.motorisation_available_torque_Nm == Approx(static_cast<double>(available)).epsilon(1e-14));
  CHECK(r.motorisation_margin == Approx(static_cast<double>(available / t_min - 1)).epsilon(1e-9));
  // The motor's declared stall torque that meets the factors exactly: the derating and the speed
  // line's share at the prescribed speed give T_min.
  CHECK(r.motorisation_stall_torque_Nm == Approx(static_cast<double>(t_min / (0.85L * (1 - N * 2 * kPi * v / h / 600)))).epsilon(1e-9));
  CHECK(r.motor_torque_margin_Nm == Approx(static_cast<double>(available - needed)).epsilon(1e-9));
  // The prescribed motion does not see the train: the loads are the ideal drive's, to the bit.
  sim::SceneOptions ideal = s;
  ideal.drive = model::DriveParams{};
  const sim::RunResult i = sim::simulate(ideal);
  CHECK(i.peak_drive_force_N == r.peak_drive_force_N);
  CHECK(i.peak_static_drive_torque_Nm == r.peak_static_drive_torque_Nm);
  CHECK(i.peak_motor_torque_Nm == i.peak_drive_torque_Nm);  // an ideal train: the screw torque
}

TEST_CASE("motorisation margin: defined in motor and torque modes, negative for a motor that stalls", "[unit][drive]") {
  sim::SceneOptions s;
  s.mast.n_bays = 3;
  s.run.output_step_s = 0.0;
  s.drive.mode = model::DriveMode::motor;
  s.drive.friction_torque_Nm = 2.0e-4;
  s.drive.motor_derating = 0.9;
  const sim::RunResult r = sim::simulate(s);
  REQUIRE(r.status == sim::RunStatus::ok);
  // No acceleration is required of a motor drive (T_D = 0): T_min = MF (k_S S + k_F F_R), the
  // derated stall torque available.
  const double S = r.peak_static_drive_torque_Nm, t_min = 2.0 * (1.2 * S + 3.0 * 2.0e-4);
  CHECK(r.motorisation_required_torque_Nm == Approx(t_min).epsilon(1e-15));
  CHECK(r.motorisation_available_torque_Nm == 0.9 * 0.02);
  CHECK(r.motorisation_margin == Approx(0.9 * 0.02 / t_min - 1.0).epsilon(1e-15));
  CHECK(r.motorisation_stall_torque_Nm == Approx(t_min / 0.9).epsilon(1e-15));
  CHECK(std::isnan(r.motor_torque_margin_Nm));  // the velocity mode's quasi-static stall margin
  // A motor that crept to rest against the springs stalled: it does not meet the factor.
  sim::SceneOptions weak = s;
  weak.drive.stall_torque_Nm = 0.0044;
  const sim::RunResult w = sim::simulate(weak);
  REQUIRE(w.status == sim::RunStatus::stall);
  CHECK(w.motorisation_margin < 0.0);
  // Torque mode judges its constant torque.
  s.drive.mode = model::DriveMode::torque;
  const sim::RunResult t = sim::simulate(s);
  REQUIRE(t.status == sim::RunStatus::ok);
  CHECK(t.motorisation_available_torque_Nm == s.drive.torque_Nm);
  CHECK(std::isnan(t.motorisation_stall_torque_Nm));  // a constant torque has no stall torque
  CHECK(t.motorisation_margin == Approx(s.drive.torque_Nm / (2.0 * (1.2 * t.peak_static_drive_torque_Nm + 3.0 * 2.0e-4)) - 1.0)
                                     .epsilon(1e-15));
  // The torque the motor must give is the actuator's own, both ways: the largest force along the
  // run direction (the peak deploying, minus the minimum retracting) through the train's inverse.
  s.drive.gear_ratio = 2.0;
  s.drive.screw_efficiency = 0.5;
  for (const auto dir : {model::Direction::deploy, model::Direction::retract}) {
    s.run.direction = dir;
    const sim::RunResult a = sim::simulate(s);
    REQUIRE(a.status == sim::RunStatus::ok);
    CHECK(a.peak_motor_torque_Nm == Approx(s.drive.torque_Nm).epsilon(1e-14));
  }
  s.run.direction = model::Direction::deploy;
  // An ideal retraction: the springs help and nothing resists, no factor to meet.
  sim::SceneOptions back;
  back.mast.n_bays = 3;
  back.run.output_step_s = 0.0;
  back.run.direction = model::Direction::retract;
  const sim::RunResult b = sim::simulate(back);
  REQUIRE(b.status == sim::RunStatus::ok);
  CHECK(b.peak_static_drive_torque_Nm <= 0.0);   // the diagonals pull the mast down: they help
  CHECK(b.peak_inertial_drive_torque_Nm <= 0.0);  // at constant speed, nothing to accelerate
  CHECK(b.motorisation_required_torque_Nm == 0.0);
  CHECK(std::isnan(b.motorisation_margin));
  // With friction the motor has a resistance to meet, retracting too: MF k_F F_R.
  back.drive.friction_torque_Nm = 1e-3;
  const sim::RunResult f = sim::simulate(back);
  CHECK(f.motorisation_required_torque_Nm == Approx(2.0 * 3.0 * 1e-3).epsilon(1e-15));
  CHECK(f.motorisation_margin == Approx(f.motor_torque_at_speed_Nm / 6e-3 - 1.0).epsilon(1e-14));
  // At or above the motor's no-load speed no stall torque gives the prescribed speed.
  back.drive.no_load_speed_rad_per_s = 0.9 * 2.0 * M_PI * back.drive.speed_m_per_s / back.drive.screw_lead_m;
  const sim::RunResult fast = sim::simulate(back);
  CHECK(fast.motorisation_stall_torque_Nm == std::numeric_limits<double>::infinity());
  CHECK(fast.motorisation_margin <= -1.0);
}
