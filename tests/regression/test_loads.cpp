// The loads of one run pinned to values derived by hand, independently of the code under test:
// the drive torque of the screw, the pin force
// on the rail, the diagonal tension at the lock and the blanket's mass at the start of a run
// with panels. Each check names the derivation it relies on.
#include <catch2/catch.hpp>

#include <cmath>

#include "model/rail.hpp"
#include "sim/simulate.hpp"

using namespace truss;
using namespace truss::sim;

namespace {
SceneOptions scene(DriveMode mode, int n_bays) {
  SceneOptions s;
  s.mast.n_bays = n_bays;
  s.drive.mode = mode;
  s.run.output_step_s = 0.0;
  return s;
}
}  // namespace

TEST_CASE("drive torque: a screw of lead h turns force F into torque F h / (2 pi)", "[loads][torque]") {
  // One turn (2 pi rad) advances the nut by h: virtual work T dphi = F dy with dy = h dphi / (2 pi).
  SECTION("velocity mode: the torque columns are the force columns times h / (2 pi)") {
    const SceneOptions s = scene(DriveMode::velocity, 5);
    const RunResult r = simulate(s);
    REQUIRE(r.status == RunStatus::ok);
    const double h = s.drive.screw_lead_m;
    CHECK(r.peak_drive_torque_Nm == Approx(r.peak_drive_force_N * h / (2.0 * M_PI)).epsilon(1e-14));
    CHECK(r.min_drive_torque_Nm == Approx(r.min_drive_force_N * h / (2.0 * M_PI)).epsilon(1e-14));
  }
  SECTION("torque mode: the drive force is 2 pi T / h and the peak torque is T") {
    const SceneOptions s = scene(DriveMode::torque, 5);
    const RunResult r = simulate(s);
    REQUIRE(r.status == RunStatus::ok);
    CHECK(r.peak_drive_force_N == Approx(2.0 * M_PI * s.drive.torque_Nm / s.drive.screw_lead_m).epsilon(1e-14));
    CHECK(r.peak_drive_torque_Nm == Approx(s.drive.torque_Nm).epsilon(1e-14));
  }
}

TEST_CASE("pin force: the rail multiplier shared by three pins along the rail normal", "[loads][pin]") {
  // The rail f = y_h - y_l + cot(beta) (x_h - x_l) has gradient (cot beta, 1) in the hinge
  // coordinates; its multiplier lambda is the force lambda (cot beta, 1) that the three pins exert
  // together along the rail normal, so one pin carries |lambda| |(cot beta, 1)| / 3 =
  // |lambda| / (3 sin beta) (not cos: at beta = 20.85 deg they differ by a factor 2.6).
  for (double beta_deg : {5.0, 20.85, 40.0}) {
    model::RailParams r;
    r.beta_rad = beta_deg * M_PI / 180.0;
    const double c = 1.0 / std::tan(r.beta_rad);
    for (double lambda : {-3.0, 0.7, 12.5}) {
      const double want = std::abs(lambda) * std::hypot(c, 1.0) / 3.0;
      CHECK(model::calc_pin_force_N(r, lambda) == Approx(want).epsilon(1e-14));
      CHECK(model::calc_pin_force_N(model::calc_rail_constants(r), lambda) == Approx(want).epsilon(1e-14));  // the phases' form
    }
  }
}

TEST_CASE("diagonal tension: its peak is the spring at the straight bay", "[loads][tension]") {
  // Equal triangular frames of side b: a diagonal spans one face, horizontal offset b; at the lock
  // the bay is straight (D = 2 l_s) and the diagonal longest, sqrt(4 l_s^2 + b^2), so the largest
  // tension of a deployment is K (sqrt(4 l_s^2 + b^2) - l_0) (linear spring, taut there).
  for (DriveMode mode : {DriveMode::velocity, DriveMode::torque}) {
    const SceneOptions s = scene(mode, 4);
    const RunResult r = simulate(s);
    REQUIRE(r.status == RunStatus::ok);
    const double l = s.mast.strut_length_m, b = s.mast.frame_side_m;
    const double want = s.mast.diagonal_stiffness_N_per_m * (std::sqrt(4.0 * l * l + b * b) - s.mast.diagonal_free_length_m);
    REQUIRE(want > 0.0);
    // The peak is refined on the phase's interpolant up to the lock, where it sits: 1e-9 relative
    // covers the located lock (event tolerance 1e-13 s) in torque mode; velocity mode is exact.
    CHECK(r.peak_diagonal_tension_N == Approx(want).epsilon(1e-9));
  }
}

TEST_CASE("panels: the blanket's mass at the start is M_p(h_tip), the height offset included", "[loads][panels]") {
  // Velocity mode starts the driven part from rest by an impulse J = M_yy v (docs/model.md §4). With a
  // blanket the driven coordinate carries M_p(H) more, H = y_m + h_tip = h_tip at the start
  // (frame n stowed at 0, nothing locked): docs/model.md §1 / paper eq. 2 corrected,
  //   M_p(H) = m_p/n^2 sum_k (k - 1/2)^2 + m_p H^2 / (4 n (P - H^2)) + n m_p l_p^2 / (12 (P - H^2)),
  // P = n^2 l_p^2. So J(panels) - J(none) = v M_p(h_tip), everything else being equal.
  SceneOptions bare = scene(DriveMode::velocity, 3);
  SceneOptions with = bare;
  with.panels.count = 10;
  with.panels.length_m = 0.6;
  with.panels.mass_kg = 0.2;
  with.panels.tip_height_m = 0.4;
  const RunResult a = simulate(bare), b = simulate(with);
  REQUIRE(a.status == RunStatus::ok);
  REQUIRE(b.status == RunStatus::ok);
  const double n = 10, lp = 0.6, mp = 0.2, H = 0.4, P = n * n * lp * lp;
  double folded = 0.0;
  for (int k = 1; k <= 10; ++k) folded += (k - 0.5) * (k - 0.5);
  folded *= mp / (n * n);
  const double Mp = folded + mp * H * H / (4.0 * n * (P - H * H)) + n * mp * lp * lp / (12.0 * (P - H * H));
  CHECK(b.start_drive_impulse_Ns - a.start_drive_impulse_Ns == Approx(with.drive.speed_m_per_s * Mp).epsilon(1e-12));
}
