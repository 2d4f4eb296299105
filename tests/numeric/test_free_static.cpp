// The free stack's static resistance (docs/model-notes.md "Resistive torque", model/static_resistance.hpp):
// the drive force that holds the stack at rest with the deploying bay in its configuration and the
// frames below it in static equilibrium. Checked against a separate computation of the potential
// energy: the diagonals' energy written again here in long double, the lower frames' equilibrium
// found by minimising it (Newton on the frame heights, a dense solve), and the drive force as the
// central difference of that minimum along the path; against the phases' own equations of motion
// at rest; and, with a single bay below the deploying one, against the held stack's value.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "free_stack/free_phase.hpp"
#include "free_stack/free_phase_b.hpp"
#include "model/rail.hpp"
#include "model/static_resistance.hpp"
#include "stages/held_phase.hpp"
#include "test_helpers.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {

using LD = long double;

// docs/model.md §1: six tension-only diagonals of length L = sqrt(b^2 + D^2), U = 3 K (L - l_0)^2,
// with b^2 = (b_lo^2 + b_lo b_up + b_up^2) / 3 for frames of sides b_lo, b_up.
struct Bay {
  LD K, l0, b2;
  LD L(LD D) const { return std::sqrt(b2 + D * D); }
  LD U(LD D) const { const LD e = L(D) - l0; return e > 0 ? 3 * K * e * e : 0; }
  LD dU(LD D) const { const LD e = L(D) - l0; return e > 0 ? 6 * K * e * D / L(D) : 0; }
  LD d2U(LD D) const {
    const LD l = L(D), e = l - l0;
    return e > 0 ? 6 * K * (D * D / (l * l) + e * b2 / (l * l * l)) : 0;
  }
};

std::vector<Bay> bays_of(const model::MastParams& mast) {
  std::vector<Bay> b(1);  // b[i] is bay i
  for (int i = 1; i <= mast.n_bays(); ++i) {
    const LD s0 = mast.frame(i - 1).side_m, s1 = mast.frame(i).side_m;
    b.push_back({mast.bay(i).diagonal_stiffness_N_per_m, mast.bay(i).diagonal_free_length_m, (s0 * s0 + s0 * s1 + s1 * s1) / 3});
  }
  return b;
}

// Frame 0 at 0, frame top at y_top, frames 1..top-1 free: the heights that minimise the energy of
// bays 1..top (all taut), by Newton's method on the gradient U_k'(D_k) - U_{k+1}'(D_{k+1}).
std::vector<LD> equilibrium(const std::vector<Bay>& b, int top, LD y_top) {
  std::vector<LD> y(static_cast<std::size_t>(top + 1));
  for (int k = 0; k <= top; ++k) y[k] = y_top * k / top;
  const int n = top - 1;
  for (int it = 0; it < 60 && n > 0; ++it) {
    Eigen::Matrix<LD, Eigen::Dynamic, Eigen::Dynamic> H = Eigen::Matrix<LD, Eigen::Dynamic, Eigen::Dynamic>::Zero(n, n);
    Eigen::Matrix<LD, Eigen::Dynamic, 1> g(n);
    for (int k = 1; k < top; ++k) {
      const LD Dk = y[k] - y[k - 1], Du = y[k + 1] - y[k];
      g[k - 1] = b[k].dU(Dk) - b[k + 1].dU(Du);
      H(k - 1, k - 1) = b[k].d2U(Dk) + b[k + 1].d2U(Du);
      if (k > 1) H(k - 1, k - 2) = H(k - 2, k - 1) = -b[k].d2U(Dk);
    }
    const Eigen::Matrix<LD, Eigen::Dynamic, 1> dy = H.partialPivLu().solve(-g);
    for (int k = 1; k < top; ++k) y[k] += dy[k - 1];
    if (dy.cwiseAbs().maxCoeff() < 1e-19L) break;
  }
  return y;
}

LD chain_energy(const std::vector<Bay>& b, const std::vector<LD>& y) {
  LD V = 0;
  for (std::size_t k = 1; k < y.size(); ++k) V += b[k].U(y[k] - y[k - 1]);
  return V;
}

// The rail of docs/model.md §1 in long double: hinge at offset x on y_h = y_r - c x, frames at y_h +- s.
struct Rail {
  LD c, yr, l;
  LD s(LD x) const { return std::sqrt(l * l - x * x); }
  LD Y(LD x) const { return yr - c * x + s(x); }
  LD Z(LD x) const { return yr - c * x - s(x); }
};

stages::PhaseContext context(const model::MastParams& mast, stages::PhaseKind kind, int m) {
  stages::PhaseContext ctx;
  ctx.mast = &mast; ctx.kind = kind; ctx.bay = m; ctx.locked_mass_kg = 1.3;
  ctx.drive.mode = model::DriveMode::velocity;
  ctx.drive.speed_m_per_s = 0.0;  // at rest: no Baumgarte pull towards a drive speed
  return ctx;
}

}  // namespace

// Central differences: truncation h^2 |V'''| / 6 with |V'''| < 1e3 N/m^2 here, rounding of the
// long-double energies eps_ld |V| / h with eps_ld = 1.1e-19 and |V| < 2 J; their balance
// h = (3 eps_ld |V| / |V'''|)^(1/3) ~ 1e-7 m gives an error near 1e-11 N. The drive forces under
// test are double (rounding ~1e-15 N). Tolerance 1e-9 relative and 1e-9 N: two orders above the
// estimate, and far below what a missing term moves (the chain's pull contributes 0.1-1 N here).
TEST_CASE("free stack static drive force: central differences of the potential's minimum, and the "
          "phases at rest", "[numeric][free][margins]") {
  model::MastParams mast = testing::make_uneven_mast(5);
  for (auto& b : mast.bays) b.diagonal_free_length_m *= 0.37 / 0.45;  // taut from D ~ 0.085 m
  mast.rail.y_m += 0.4;                                                // y_r ~ 0.76 m: bays 1..3 span 0.35-0.58 m
  const std::vector<Bay> B = bays_of(mast);
  const int m = 4;
  const LD h = 1e-7L;
  Eigen::VectorXd acc(m);

  SECTION("off the rail: F = dV*/dy_m, V* the energy with frames 1..m-1 at rest") {
    const std::vector<model::BayConstants> table = model::calc_bay_table(mast);
    const stages::FreePhaseA a(context(mast, stages::PhaseKind::open, m), 1, 0.0, table);
    for (LD y_top : {0.45L, 0.55L, 0.65L}) {
      const LD fd = (chain_energy(B, equilibrium(B, m, y_top + h)) - chain_energy(B, equilibrium(B, m, y_top - h))) / (2 * h);
      const std::vector<LD> y = equilibrium(B, m, y_top);
      const double q[4] = {double(y[1]), double(y[2]), double(y[3]), double(y[4])}, qd[4] = {0, 0, 0, 0};
      stages::PhaseScratch sys;
      const stages::PhasePoint p = a.calc_point(q, qd, acc.data(), sys);
      INFO("y_m " << double(y_top) << " F " << p.static_drive_force_N << " fd " << double(fd));
      CHECK(p.static_drive_force_N == Approx(double(fd)).epsilon(1e-9).margin(1e-9));
      CHECK(fd > 0.1);  // the diagonals pull: the check is not 0 == 0
      // At rest in that configuration the equations of motion need exactly this drive force, and
      // leave every frame at rest (heights rounded to double: 1e-17 m x U'' ~ 1e-15 N).
      CHECK(p.drive_force_N == Approx(p.static_drive_force_N).epsilon(1e-12).margin(1e-13));
      CHECK(acc.cwiseAbs().maxCoeff() < 1e-12);
    }
  }
  SECTION("on the rail: F = dV*/dY along the rail, frames 1..m-2 at rest below frame m-1 at Z(x)") {
    const std::vector<model::BayConstants> table = model::calc_bay_table(mast);
    const stages::FreePhaseB b(context(mast, stages::PhaseKind::on_rail, m), 1, 0.0, 10.0, table);
    const Rail r{1 / std::tan(LD(mast.rail.beta_rad)), mast.rail.y_m + mast.rail.x_m / std::tan(LD(mast.rail.beta_rad)),
                 mast.bay(m).strut_length_m};
    auto V = [&](LD x) { return B[m].U(r.Y(x) - r.Z(x)) + chain_energy(B, equilibrium(B, m - 1, r.Z(x))); };
    int n_pull = 0;
    for (LD x : {0.1L, 0.06L, 0.02L, 0.0L}) {
      const LD fd = (V(x + h) - V(x - h)) / (r.Y(x + h) - r.Y(x - h));
      const std::vector<LD> y = equilibrium(B, m - 1, r.Z(x));
      const double q[4] = {double(y[1]), double(y[2]), double(y[3]), double(x)}, qd[4] = {0, 0, 0, 0};
      stages::PhaseScratch sys;
      const stages::PhasePoint p = b.calc_point(q, qd, acc.data(), sys);
      const LD pull = B[1].dU(y[1] - y[0]);
      INFO("x " << double(x) << " F " << p.static_drive_force_N << " fd " << double(fd) << " chain pull " << double(pull));
      CHECK(p.static_drive_force_N == Approx(double(fd)).epsilon(1e-9).margin(1e-9));
      const double span = double(r.Z(x));
      CHECK(model::calc_chain_pull_N(mast, 1, m - 1, span, model::calc_chain_slack_span_m(mast, 1, m - 1)) ==
            Approx(double(pull)).epsilon(1e-12));
      n_pull += pull > 0.1;
      CHECK(p.drive_force_N == Approx(p.static_drive_force_N).epsilon(1e-12).margin(1e-13));
      CHECK(acc.cwiseAbs().maxCoeff() < 1e-10);
    }
    CHECK(n_pull == 4);  // the chain below pulls at every point: its term is tested
  }
  SECTION("on the rail with a chain that can be slack: only the deploying bay resists") {
    model::MastParams t1 = testing::make_uneven_mast(5);  // Table 1's l_0 ~ 0.45 m: taut from D ~ 0.27 m
    const std::vector<Bay> B1 = bays_of(t1);
    const std::vector<model::BayConstants> table = model::calc_bay_table(t1);
    const stages::FreePhaseB b(context(t1, stages::PhaseKind::on_rail, m), 1, 0.0, 10.0, table);
    const Rail r{1 / std::tan(LD(t1.rail.beta_rad)), t1.rail.y_m + t1.rail.x_m / std::tan(LD(t1.rail.beta_rad)),
                 t1.bay(m).strut_length_m};
    LD slack = 0;
    for (int i = 1; i < m; ++i) slack += std::sqrt(B1[i].l0 * B1[i].l0 - B1[i].b2);
    for (LD x : {0.06L, 0.03L}) {
      REQUIRE(r.Z(x) < slack);  // bays 1..m-1 can all be slack: the chain's minimum energy is 0
      const LD fd = (B1[m].U(2 * r.s(x + h)) - B1[m].U(2 * r.s(x - h))) / (r.Y(x + h) - r.Y(x - h));
      const double q[4] = {0.01, 0.02, double(r.Z(x)), double(x)}, qd[4] = {0, 0, 0, 0};
      stages::PhaseScratch sys;
      const stages::PhasePoint p = b.calc_point(q, qd, acc.data(), sys);
      INFO("x " << double(x) << " F " << p.static_drive_force_N << " fd " << double(fd));
      CHECK(p.static_drive_force_N == Approx(double(fd)).epsilon(1e-9).margin(1e-9));
      CHECK(fd > 0.1);
    }
  }
}

TEST_CASE("free stack static drive force with one bay below the deploying one is the held stack's",
          "[numeric][free][margins]") {
  // Stage of bay 2: frame 0 on the floor, frame 1 on the rail: the chain below is bay 1 alone, the
  // held stack's lower bay. Both evaluate the same expressions in other orders (rounding ~1e-15 N).
  model::MastParams mast = testing::make_uneven_mast(3);
  for (auto& b : mast.bays) b.diagonal_free_length_m *= 0.37 / 0.45;  // bay 1 taut on the rail too
  stages::PhaseContext ctx = context(mast, stages::PhaseKind::on_rail, 2);
  const stages::HeldPhase held(ctx);
  const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
  const stages::FreePhaseB fr(ctx, 1, 0.0, 10.0, table);
  const model::RailConstants rc = model::calc_rail_constants(mast.rail);
  Eigen::VectorXd acc(2);
  int n_lower = 0;
  for (double x : {0.07, 0.02, 0.01, 0.0}) {
    const model::OnRailKinematics k = model::calc_on_rail(rc, mast.bay(2).strut_length_m, x);
    const double q[2] = {k.Z, x}, qd[2] = {0, 0};
    stages::PhaseScratch sys;
    const double Ff = fr.calc_point(q, qd, acc.data(), sys).static_drive_force_N;
    const double Fh = held.calc_point(x, 0.0).static_drive_force_N;
    INFO("x " << x << " free " << Ff << " held " << Fh);
    CHECK(Ff == Approx(Fh).epsilon(1e-12).margin(1e-14));
    n_lower += model::calc_bay_dU_dD_N(mast.bay(1), model::calc_diagonal_offset_sq_m2(mast.frame(0), mast.frame(1)), k.Z) > 0.1;
  }
  CHECK(n_lower >= 2);  // bay 1 pulls: the lower bay's term is compared
}

TEST_CASE("free stack on the rail with a taut two-bay chain below: what the inertial part holds",
          "[numeric][free][margins]") {
  // docs/model-notes.md ("Resistive torque of the free stack"): the inertial part, F - F_static, is
  // (F - F_rest) + (U'_{m-1}(D_{m-1}) - P) Z'(x) / Y'(x): F_rest the drive force that holds the
  // present configuration at rest with every frame where it is (the spring terms: dV/dY along the
  // rail with the frames below m-1 fixed, V the potential written again here), so F - F_rest is the
  // inertia and velocity terms; the second term is the pull of bay m-1 beyond the chain's
  // equilibrium tension P (found here by minimising the chain's energy). Stage of bay 3: bays 1 and 2
  // below it, taut. Tolerances as above (central differences, 1e-9).
  model::MastParams mast = testing::make_uneven_mast(5);
  for (auto& b : mast.bays) b.diagonal_free_length_m *= 0.37 / 0.45;  // taut from D ~ 0.085 m
  mast.rail.y_m += 0.4;
  const std::vector<Bay> B = bays_of(mast);
  const int m = 3;
  const LD h = 1e-7L;
  const std::vector<model::BayConstants> table = model::calc_bay_table(mast);
  const stages::FreePhaseB b(context(mast, stages::PhaseKind::on_rail, m), 1, 0.0, 10.0, table);
  const Rail r{1 / std::tan(LD(mast.rail.beta_rad)), mast.rail.y_m + mast.rail.x_m / std::tan(LD(mast.rail.beta_rad)),
               mast.bay(m).strut_length_m};
  Eigen::VectorXd acc(3);
  int n_spring = 0;
  for (const LD x : {0.08L, 0.03L}) {
    const std::vector<LD> eq = equilibrium(B, m - 1, r.Z(x));
    const LD P = B[1].dU(eq[1] - eq[0]), Zp = -r.c + x / r.s(x), Yp = -r.c - x / r.s(x);
    REQUIRE(P > 0.1);  // the chain is taut
    for (const LD d : {0.0L, 0.01L, -0.015L}) {
      for (const double speed : {0.0, 0.02}) {
        const LD y1 = eq[1] + d;
        auto V_rest = [&](LD xx) { return B[m].U(r.Y(xx) - r.Z(xx)) + B[2].U(r.Z(xx) - y1) + B[1].U(y1); };
        const LD F_rest = (V_rest(x + h) - V_rest(x - h)) / (r.Y(x + h) - r.Y(x - h));
        const LD spring = (B[2].dU(r.Z(x) - y1) - P) * Zp / Yp;
        const double q[3] = {double(y1), double(r.Z(x)), double(x)}, qd[3] = {speed, -0.5 * speed, speed};
        stages::PhaseScratch sys;
        const stages::PhasePoint p = b.calc_point(q, qd, acc.data(), sys);
        const double inertial = p.drive_force_N - p.static_drive_force_N;
        INFO("x " << double(x) << " d " << double(d) << " speed " << speed << " inertial " << inertial << " spring "
                  << double(spring) << " F - F_rest " << p.drive_force_N - double(F_rest));
        CHECK(inertial == Approx(p.drive_force_N - double(F_rest) + double(spring)).margin(1e-9));
        if (d == 0.0L) {
          CHECK(std::fabs(spring) < 1e-12L);  // the chain in equilibrium: no spring term
          if (speed == 0.0) CHECK(std::fabs(inertial) < 1e-10);  // and at rest nothing accelerates
        } else {
          n_spring += std::fabs(spring) > 0.1L;
        }
      }
    }
  }
  CHECK(n_spring >= 6);  // out of equilibrium the spring term is there and large
}
