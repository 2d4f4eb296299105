// The free stack's phase A (free_stack/free_phase.hpp) integrated as an ODE: the energy balance
// T + U - W = const (no impact, no contact in the interval) checks the tridiagonal mass matrix,
// the velocity terms and the O(n) solve together, independently of how they are written: a wrong
// coefficient in M or r breaks the balance at first order in time.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "integrators/dopri54.hpp"
#include "sim/scene.hpp"
#include "free_stack/free_phase.hpp"
#include "free_stack/free_phase_b.hpp"
#include "stages/peaks.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {

class FreeOde : public integrators::OdeSystem {
 public:
  explicit FreeOde(const stages::PhaseModel& p) : p_(p), n_(p.dof()) {}
  int size() const override { return 2 * n_ + 1; }
  void calc_rhs(double, const double* y, double* dy) override {
    const stages::PhasePoint pt = p_.calc_point(y, y + n_, dy + n_, scratch_);
    for (int k = 0; k < n_; ++k) dy[k] = y[n_ + k];
    dy[2 * n_] = pt.drive_force_N * pt.u_m_per_s;
  }
  stages::PhasePoint point(const double* y) const {
    std::vector<double> acc(static_cast<std::size_t>(n_));
    stages::PhaseScratch s;
    return p_.calc_point(y, y + n_, acc.data(), s);
  }

 private:
  const stages::PhaseModel& p_;
  int n_;
  stages::PhaseScratch scratch_;
};

// An uneven 6-bay mast (per-bay masses, inertias, stiffnesses, frame sides).
model::MastParams make_mast() {
  sim::SceneOptions s;
  s.mast.n_bays = 6;
  model::MastParams m = sim::build_mast(s);
  for (int i = 1; i <= 6; ++i) {
    auto& b = m.bays[static_cast<std::size_t>(i - 1)];
    b.strut_mass_kg *= 1.0 + 0.07 * i;
    b.strut_inertia_kg_m2 *= 1.0 + 0.11 * i;
    b.diagonal_stiffness_N_per_m *= 1.0 + 0.2 * i;
  }
  for (int k = 0; k <= 6; ++k) m.frames[static_cast<std::size_t>(k)].mass_kg *= 1.0 + 0.05 * k;
  m.frames[3].side_m = 0.38;
  return m;
}

// The free phases' context of bay 6 of make_mast(): the tip locked to frame 6, a drive of that mode
// (a torque drive's 10 mN m; the velocity drive does not read it).
stages::PhaseContext bay6_context(const model::MastParams& mast, stages::PhaseKind kind, model::DriveMode mode) {
  stages::PhaseContext ctx;
  ctx.mast = &mast;
  ctx.bay = 6;
  ctx.kind = kind;
  ctx.locked_mass_kg = mast.tip_mass_kg;
  ctx.drive.mode = mode;
  ctx.drive.torque_Nm = 0.01;
  return ctx;
}

}  // namespace

TEST_CASE("free phase A: energy balance of the n-DOF system under a torque and a motor drive", "[numeric][free]") {
  const model::MastParams mast = make_mast();
  for (auto mode : {model::DriveMode::torque, model::DriveMode::motor}) {
    const stages::PhaseContext ctx = bay6_context(mast, stages::PhaseKind::open, mode);
    const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
    const stages::FreePhaseA phase(ctx, 1, 0.0, table);
    REQUIRE(phase.dof() == 6);
    FreeOde ode(phase);
    // Start: frames slightly open (diagonals of bays 4-6 taut from D = 0.27 m) and moving.
    std::vector<double> y = {0.01, 0.03, 0.06, 0.33, 0.62, 0.91, 0.0, 0.01, -0.02, 0.05, 0.0, 0.08, 0.0};
    const stages::PhasePoint p0 = ode.point(y.data());
    integrators::IntegratorOptions o;
    o.rtol = 1e-12;
    o.atol = 1e-14;
    integrators::DormandPrince54 dp(o);
    const auto sum = dp.integrate(ode, 0.0, 0.2, y.data(), nullptr);
    REQUIRE(sum.status == integrators::IntegratorStatus::reached_end);
    const stages::PhasePoint p1 = ode.point(y.data());
    const double W = y[12];
    const double drift = (p1.kinetic_energy_J + p1.potential_energy_J - W) - (p0.kinetic_energy_J + p0.potential_energy_J);
    INFO("mode " << model::to_string(mode) << " W " << W << " T1 " << p1.kinetic_energy_J << " U1 " << p1.potential_energy_J);
    CHECK(std::abs(W) > 1e-3);  // the drive did work: the check is not vacuous
    // Global error ~ rtol * (number of steps) * energy scale: 1e-9 of the work leaves a margin.
    CHECK(std::abs(drift) < 1e-9 * std::max(1.0, std::abs(W)));
  }
}

TEST_CASE("free phase A in velocity mode: the driven frame keeps its speed, the drive force is the inverse dynamics",
          "[numeric][free]") {
  const model::MastParams mast = make_mast();
  const stages::PhaseContext ctx = bay6_context(mast, stages::PhaseKind::open, model::DriveMode::velocity);
  const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
  const stages::FreePhaseA phase(ctx, 1, 0.0, table);
  FreeOde ode(phase);
  std::vector<double> y = {0.01, 0.03, 0.06, 0.33, 0.62, 0.91, 0.0, 0.01, -0.02, 0.05, 0.0, 0.1, 0.0};
  const stages::PhasePoint p0 = ode.point(y.data());
  integrators::IntegratorOptions o;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  integrators::DormandPrince54 dp(o);
  REQUIRE(dp.integrate(ode, 0.0, 0.3, y.data(), nullptr).status == integrators::IntegratorStatus::reached_end);
  CHECK(y[11] == Approx(0.1).epsilon(1e-14));           // y_m'' = 0
  CHECK(y[5] == Approx(0.91 + 0.1 * 0.3).epsilon(1e-12));
  const stages::PhasePoint p1 = ode.point(y.data());
  const double drift = (p1.kinetic_energy_J + p1.potential_energy_J - y[12]) - (p0.kinetic_energy_J + p0.potential_energy_J);
  CHECK(std::abs(y[12]) > 1e-3);
  CHECK(std::abs(drift) < 1e-9 * std::max(1.0, std::abs(y[12])));
}

#include "model/rail.hpp"
#include "free_stack/free_phase_b.hpp"
#include "stages/held_phase.hpp"

TEST_CASE("free phase B with the frames below held equals the held stack's rail phase (independent elimination)",
          "[numeric][free]") {
  // HeldPhase eliminates the multiplier in (y_m, x); FreePhaseB solves the bordered system in
  // (y_{m-1}, x). On a consistent state (f = 0, f' = 0) they must give the same x'', lambda and
  // drive force, down to the lock; 1e-10 relative covers the rounding of two formulations.
  const model::MastParams mast = make_mast();
  for (auto mode : {model::DriveMode::torque, model::DriveMode::velocity}) {
    stages::PhaseContext ctx;
    ctx.mast = &mast;
    ctx.kind = stages::PhaseKind::on_rail;
    ctx.bay = 4;
    ctx.lower_held_height_m = 0.02;  // frame 2, held
    ctx.locked_mass_kg = 2.3;
    ctx.drive.mode = mode;
    ctx.drive.torque_Nm = 0.01;
    const stages::HeldPhase held(ctx);
    const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
    const stages::FreePhaseB free(ctx, 3, 0.02, 10.0, table);
    const double l = mast.bay(4).strut_length_m;
    for (double x : {0.07, 0.03, 0.004, 1e-7, 0.0}) {
      const auto k = model::calc_on_rail(mast.rail, l, x);
      const double xi = mode == model::DriveMode::velocity ? 0.1 / k.dY : -0.7;
      const stages::PhasePoint ph = held.calc_point(x, xi);
      const double q[2] = {k.Z, x}, qd[2] = {k.dZ * xi, xi};
      double acc[2];
      stages::PhaseScratch scratch;
      const stages::PhasePoint pf = free.calc_point(q, qd, acc, scratch);
      INFO("mode " << model::to_string(mode) << " x " << x);
      CHECK(pf.rail_residual_m < 1e-15);
      CHECK(acc[1] == Approx(ph.qddot).epsilon(1e-10).margin(1e-12));
      CHECK(pf.lambda_N == Approx(ph.lambda_N).epsilon(1e-10).margin(1e-12));
      CHECK(pf.drive_force_N == Approx(ph.drive_force_N).epsilon(1e-10).margin(1e-12));
      CHECK(pf.kinetic_energy_J == Approx(ph.kinetic_energy_J).epsilon(1e-12));
      CHECK(pf.u_m_per_s == Approx(ph.u_m_per_s).epsilon(1e-13).margin(1e-15));
      // y_{m-1}'' from the free solve equals Z'(x) x'' + Z''(x) x'^2 of the held kinematics
      CHECK(acc[0] == Approx(k.dZ * acc[1] + k.d2Z * xi * xi).epsilon(1e-10).margin(1e-12));
    }
  }
}

TEST_CASE("free phase B: energy balance and rail residual of the n-DOF DAE under a torque drive", "[numeric][free]") {
  const model::MastParams mast = make_mast();
  const stages::PhaseContext ctx = bay6_context(mast, stages::PhaseKind::open, model::DriveMode::torque);
  const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
  const stages::FreePhaseB phase(ctx, 1, 0.0, 10.0, table);
  REQUIRE(phase.dof() == 6);
  FreeOde ode(phase);
  const double l = mast.bay(6).strut_length_m, x0 = 0.06, c = mast.rail.cot_beta();
  const auto k = model::calc_on_rail(mast.rail, l, x0);
  const double xi0 = -0.3;
  // Free frames 1..4 anywhere (opened, moving); frame 5 on the rail with f' = 0.
  std::vector<double> y = {0.01, 0.03, 0.05, 0.08, k.Z, x0, 0.0, 0.01, -0.02, 0.05, k.dZ * xi0, xi0, 0.0};
  REQUIRE(std::abs(phase.calc_rail_function_m(y.data())) < 1e-15);
  (void)c;
  const stages::PhasePoint p0 = ode.point(y.data());
  integrators::IntegratorOptions o;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  integrators::DormandPrince54 dp(o);
  double max_f = 0.0;
  for (int i = 1; i <= 10; ++i) {
    REQUIRE(dp.integrate(ode, 0.01 * (i - 1), 0.01 * i, y.data(), nullptr).status == integrators::IntegratorStatus::reached_end);
    max_f = std::max(max_f, std::abs(phase.calc_rail_function_m(y.data())));
  }
  REQUIRE(y[5] > 0.0);  // still short of the lock
  const stages::PhasePoint p1 = ode.point(y.data());
  const double drift = (p1.kinetic_energy_J + p1.potential_energy_J - y[12]) - (p0.kinetic_energy_J + p0.potential_energy_J);
  INFO("W " << y[12] << " drift " << drift << " max |f| " << max_f);
  CHECK(std::abs(y[12]) > 1e-3);
  CHECK(std::abs(drift) < 1e-9 * std::max(1.0, std::abs(y[12])));
  CHECK(max_f < 1e-11);  // Baumgarte-stabilised: the residual stays at the integration error
}

TEST_CASE("free phases answer a state asked again with the bits of a fresh phase's evaluation", "[numeric][free]") {
  // The phases keep their last solve (free_phase_work.hpp, MotionMemo): a state asked again, from
  // another caller's scratch, must give what a phase that never saw it gives, bit for bit, in the
  // point (loads, energies, mass terms) and the accelerations; a state in between must not leak.
  const model::MastParams mast = make_mast();
  for (auto kind : {stages::PhaseKind::open, stages::PhaseKind::on_rail}) {
    const stages::PhaseContext ctx = bay6_context(mast, kind, model::DriveMode::velocity);
    const bool a = kind == stages::PhaseKind::open;
    const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
    const stages::FreePhaseA pa(ctx, 1, 0.0, table), fresh_a(ctx, 1, 0.0, table);
    const stages::FreePhaseB pb(ctx, 1, 0.0, 10.0, table), fresh_b(ctx, 1, 0.0, 10.0, table);
    const stages::PhaseModel& used = a ? static_cast<const stages::PhaseModel&>(pa) : pb;
    const stages::PhaseModel& fresh = a ? static_cast<const stages::PhaseModel&>(fresh_a) : fresh_b;
    const int n = used.dof();
    // Frames slightly open and moving; in phase B the last coordinate is the hinge offset x.
    std::vector<double> q = {0.01, 0.03, 0.06, 0.33, 0.62, 0.91}, v = {0.0, 0.01, -0.02, 0.05, 0.0, 0.1};
    if (!a) { q[5] = 0.05; v[5] = -0.02; }
    std::vector<double> q2 = q;
    q2[3] += 1e-3;
    std::vector<double> acc(6), acc2(6), acc_fresh(6);
    stages::PhaseScratch s1, s2, s3, s4;
    used.calc_motion(q.data(), v.data(), acc.data(), s1);   // the integrator's stage at q
    used.calc_point(q2.data(), v.data(), acc2.data(), s2);  // another state in between
    used.calc_motion(q.data(), v.data(), acc.data(), s1);
    const stages::PhasePoint p = used.calc_point(q.data(), v.data(), acc.data(), s3);  // asked again, other scratch
    const stages::PhasePoint pf = fresh.calc_point(q.data(), v.data(), acc_fresh.data(), s4);
    INFO((a ? "phase A" : "phase B"));
    for (int k = 0; k < n; ++k) CHECK(acc[static_cast<std::size_t>(k)] == acc_fresh[static_cast<std::size_t>(k)]);
    CHECK(p.drive_force_N == pf.drive_force_N);
    CHECK(p.lambda_N == pf.lambda_N);
    CHECK(p.kinetic_energy_J == pf.kinetic_energy_J);
    CHECK(p.potential_energy_J == pf.potential_energy_J);
    CHECK(p.mass_yy == pf.mass_yy);
    CHECK(p.diagonal_tension_N == pf.diagonal_tension_N);
    CHECK(std::isfinite(p.drive_force_N));
    CHECK(acc2 != acc);  // the state in between was a different one
  }
}

// The peaks' search skips the quantities that find_constant_quantities declares constant in a phase
// of that kind: each must have one value at every state of such a phase (here: states spread over
// phases A and B of the free stack, torque and velocity drive), and a quantity that changes from
// state to state must not be declared.
TEST_CASE("free phases: the quantities declared constant for the peaks do not change", "[numeric][free]") {
  const model::MastParams mast = make_mast();
  for (auto mode : {model::DriveMode::torque, model::DriveMode::velocity}) {
    for (auto kind : {stages::PhaseKind::open, stages::PhaseKind::on_rail}) {
      const stages::PhaseContext ctx = bay6_context(mast, kind, mode);
      const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
      const stages::FreePhaseA a(ctx, 1, 0.0, table);
      const stages::FreePhaseB b(ctx, 1, 0.0, 10.0, table);
      const stages::PhaseModel& phase = kind == stages::PhaseKind::open ? static_cast<const stages::PhaseModel&>(a) : b;
      const int n = phase.dof();
      std::vector<std::vector<double>> values(stages::kQuantityCount);
      for (int s = 0; s < 5; ++s) {  // frames opening bay by bay, moving; on the rail x from 0.17 to 0.09 m
        std::vector<double> q(static_cast<std::size_t>(n)), qd(q.size()), acc(q.size());
        for (int k = 0; k < n; ++k) {
          q[k] = 0.01 * (k + 1) + (k >= 3 ? 0.29 * (k - 2) : 0.0) + 0.003 * s * k;
          qd[k] = 0.01 * std::sin(1.3 * k + s);
        }
        if (kind == stages::PhaseKind::on_rail) { q[n - 1] = 0.17 - 0.02 * s; qd[n - 1] = -0.05 - 0.01 * s; }
        stages::PhaseScratch scratch;
        const stages::PhasePoint p = phase.calc_loads(q.data(), qd.data(), acc.data(), scratch);
        for (int i = 0; i < stages::kQuantityCount; ++i) values[i].push_back(stages::calc_peak_quantity(i, p, 1.0));
      }
      const unsigned constant = stages::find_constant_quantities(kind);
      for (int i = 0; i < stages::kQuantityCount; ++i) {
        bool same = true;
        for (double v : values[i]) same = same && (v == values[i][0] || (std::isnan(v) && std::isnan(values[i][0])));
        INFO("mode " << model::to_string(mode) << " on rail " << (kind == stages::PhaseKind::on_rail) << " quantity " << i);
        if ((constant >> i) & 1u) CHECK(same);
        if (!same) CHECK(!((constant >> i) & 1u));
      }
      CHECK(!values[stages::kForce].empty());
    }
  }
}

// The phases take the run's bay table (model::calc_bay_table of the mast they evaluate); a table of
// another mast would index past its end or read another mast's constants, so it is refused.
TEST_CASE("free phases refuse a bay table that is not their mast's", "[numeric][free]") {
  const model::MastParams mast = make_mast();
  sim::SceneOptions s;
  s.mast.n_bays = 4;
  const std::vector<model::BayConstants> other = model::calc_bay_table(sim::build_mast(s));
  const stages::PhaseContext ctx = bay6_context(mast, stages::PhaseKind::open, model::DriveMode::torque);
  CHECK_THROWS_AS(stages::FreePhaseA(ctx, 1, 0.0, other), std::invalid_argument);
  CHECK_THROWS_AS(stages::FreePhaseB(ctx, 1, 0.0, 10.0, other), std::invalid_argument);
  const std::vector<model::BayConstants> own = model::calc_bay_table(mast);
  CHECK_NOTHROW(stages::FreePhaseA(ctx, 1, 0.0, own));
}
