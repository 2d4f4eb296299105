// The free stack's second solver: SUNDIALS IDA on the residual form of the free
// phases against the direct method (the bordered tridiagonal solve of eqs. 19-20 integrated by the
// own Dormand-Prince pair). The two share the assembly of M, r and the constraint rows
// (free_phase*.cpp) but nothing after it: IDA solves the residual's Newton systems with a banded LU
// of its difference-quotient Jacobian and integrates with variable-order BDF, the direct method
// eliminates the multipliers with Thomas sweeps and integrates with an explicit RK pair.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <vector>

#include "numeric/dense_frames.hpp"
#include "sim/simulate.hpp"
#include "free_stack/free_phase.hpp"
#include "free_stack/free_phase_b.hpp"
#include "stages/phase_dynamic.hpp"
#include "test_helpers.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {

model::DriveMode mode_of(const std::string& m) {
  return m == "velocity" ? model::DriveMode::velocity : m == "torque" ? model::DriveMode::torque : model::DriveMode::motor;
}

// Residual rows of the DAE form (phase.hpp) at (q, q', q'', mu), written out densely here.
struct Residual {
  Eigen::VectorXd dyn, con;
};
Residual calc_residual(const stages::PhaseDaeTerms& t, const Eigen::VectorXd& acc, const Eigen::VectorXd& mu) {
  const Eigen::MatrixXd M = testing::dense_tridiagonal(t.diag, t.sub);
  Residual r;
  r.dyn = M * acc - t.rhs;
  r.con.resize(t.num_multipliers);
  for (int j = 0; j < t.num_multipliers; ++j) {
    r.dyn -= mu[j] * t.c[j];
    r.con[j] = t.c[j].dot(acc) - t.s[j];
  }
  return r;
}

sim::SceneOptions slack_scene(const char* mode, int n, double rtol) {
  sim::SceneOptions s;
  s.mast.n_bays = n;
  s.mast.diagonal_free_length_m = 0.49;  // paper_free_slack: deploys in every mode
  s.stack.mode = sim::StackMode::free;
  s.drive.mode = mode_of(mode);
  s.run.rtol = rtol;
  s.run.atol = 1e-2 * rtol;
  s.run.output_step_s = 0.05;  // the last history row is the final state
  return s;
}

}  // namespace

TEST_CASE("free phases: the residual form vanishes at the direct solution", "[numeric][free][ida]") {
  // The accelerations and multipliers of the direct O(n) solve must satisfy the DAE residual
  // (M q'' = r + sum mu_j c_j, c_j' q'' = s_j) to rounding: the residual uses a dense product, the
  // direct solve Thomas sweeps. A sign or index slip in either (the rail multiplier's sign, the
  // drive row, the Baumgarte term) leaves an O(1) residual.
  const model::MastParams mast = testing::make_uneven_mast(6, 0.1);
  for (const char* mode : {"velocity", "torque", "motor"}) {
    INFO(mode);
    model::DriveParams drive;
    drive.mode = mode_of(mode);
    drive.torque_Nm = 0.003;
    stages::PhaseScratch scratch;
    stages::PhaseDaeTerms t;
    {  // phase A, frames 1..6 free
      const stages::PhaseContext ctx{&mast, stages::PhaseKind::open, 6, 0.0, 1.3, 0.36, drive, 1.0, 0.0, 1.0};
      const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
      const stages::FreePhaseA a(ctx, 1, 0.0, table);
      const double q[6] = {0.02, 0.07, 0.15, 0.24, 0.33, 0.52}, qd[6] = {0.01, -0.02, 0.03, 0.05, 0.02, 0.1};
      Eigen::VectorXd acc(6);
      const stages::PhasePoint p = a.calc_point(q, qd, acc.data(), scratch);
      REQUIRE(a.calc_dae_terms(q, qd, scratch, t));
      REQUIRE(t.num_multipliers == a.num_multipliers());
      Eigen::VectorXd mu(t.num_multipliers);
      if (t.num_multipliers == 1) mu[0] = p.drive_force_N;
      const Residual r = calc_residual(t, acc, mu);
      const double scale = t.rhs.cwiseAbs().maxCoeff() + std::abs(p.drive_force_N);
      CHECK(r.dyn.cwiseAbs().maxCoeff() < 1e-12 * scale);
      if (t.num_multipliers == 1) CHECK(std::abs(r.con[0]) < 1e-14);
      CHECK((t.drive_multiplier == 0 ? mu[0] : t.drive_force_N) == Approx(p.drive_force_N).epsilon(1e-14));
    }
    {  // phase B of bay 6 on the rail: (y_1..y_5, x), slightly off the rail (Baumgarte active)
      const stages::PhaseContext ctx{&mast, stages::PhaseKind::on_rail, 6, 0.0, 1.3, 0.36, drive, 1.0, 0.0, -1.0};
      const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
      const stages::FreePhaseB b(ctx, 1, 0.0, 10.0, table);
      const double q[6] = {0.02, 0.07, 0.15, 0.24, 0.21, 0.06}, qd[6] = {0.01, -0.02, 0.03, 0.05, 0.07, -0.2};
      Eigen::VectorXd acc(6);
      const stages::PhasePoint p = b.calc_point(q, qd, acc.data(), scratch);
      REQUIRE(b.calc_dae_terms(q, qd, scratch, t));
      REQUIRE(t.num_multipliers == b.num_multipliers());
      Eigen::VectorXd mu(t.num_multipliers);
      mu[0] = p.lambda_N;
      if (t.num_multipliers == 2) mu[1] = p.drive_force_N;
      CHECK(std::abs(p.rail_residual_m) > 1e-3);  // off the rail: s_a carries the Baumgarte terms
      const Residual r = calc_residual(t, acc, mu);
      const double scale = t.rhs.cwiseAbs().maxCoeff() + std::abs(p.lambda_N) + std::abs(p.drive_force_N);
      CHECK(r.dyn.cwiseAbs().maxCoeff() < 1e-12 * scale);
      for (int j = 0; j < t.num_multipliers; ++j) CHECK(std::abs(r.con[j]) < 1e-12 * (1.0 + std::abs(t.s[j])));
      CHECK(t.driven_speed_m_per_s == Approx(p.u_m_per_s).epsilon(1e-14));
    }
  }
}

TEST_CASE("free phases: IDA's band holds the whole Jacobian of the residual form", "[numeric][free][ida]") {
  // IDA's banded solver keeps only the entries of dF/dw + c dF/dw' within the half-bandwidths the
  // phase gives (PhaseOde::find_band_order), in its order of the unknowns. Every entry outside the
  // band must be zero: each unknown w_k and each w'_k is perturbed in turn, and a residual row
  // outside the band from k must come out bit for bit the same. (A band one too narrow still
  // integrates, through Newton iterations on a wrong Jacobian: this is where it shows.) Phases A
  // and B, three drive modes, with panels, with and without stack contacts (clusters of frames as
  // coordinates).
  model::MastParams mast = testing::make_uneven_mast(8, 0.1);
  mast.panels.count = 4;
  mast.panels.length_m = 1.0;
  for (const char* mode : {"velocity", "torque", "motor"})
    for (const bool contacts : {false, true})
      for (const auto kind : {stages::PhaseKind::open, stages::PhaseKind::on_rail}) {
        INFO(mode << (contacts ? ", contacts" : "") << (kind == stages::PhaseKind::open ? ", phase A" : ", phase B"));
        model::DriveParams drive;
        drive.mode = mode_of(mode);
        const bool open = kind == stages::PhaseKind::open;
        const stages::PhaseContext ctx{&mast, kind, 8, 0.0, 1.3, 0.36, drive, 1.0, 0.0, open ? 1.0 : -1.0};
        const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
        stages::FreePhaseA a(ctx, 1, 0.0, table);
        stages::FreePhaseB b(ctx, 1, 0.0, 10.0, table);
        // Frames 1..8 (A) or 1..7 (B); clusters {1,2}, {3}, {4,5}, {6,7}, {8} (A) / {6,7} last (B).
        if (contacts) {
          a.set_contacts(stages::ContactLayout{true, {0, 2, 3, 5, 7}, 8, false, false});
          b.set_contacts(stages::ContactLayout{true, {0, 2, 3, 5}, 7, false, false});
        }
        const stages::PhaseModel& p = open ? static_cast<const stages::PhaseModel&>(a) : b;
        const auto ode = stages::make_phase_ode(p, 0.0);
        integrators::DaeForm* dae = ode->dae_form();
        REQUIRE(dae);
        const int n = p.dof(), n_ode = ode->size(), size = n_ode + dae->num_algebraic();
        std::vector<int> order;
        int lower = 0, upper = 0;
        REQUIRE(dae->find_band_order(order, lower, upper));
        REQUIRE(static_cast<int>(order.size()) == size);
        std::vector<int> pos(order.size());
        for (int k = 0; k < size; ++k) pos[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
        // A generic state, off the rail, with y' and z not consistent (the Jacobian is needed
        // everywhere Newton goes).
        std::vector<double> w(static_cast<std::size_t>(size)), wp(w.size()), r0(w.size()), r1(w.size());
        for (int i = 0; i < size; ++i) {
          w[static_cast<std::size_t>(i)] = 0.05 * (i % n + 1) + 0.01 * std::sin(i);
          wp[static_cast<std::size_t>(i)] = 0.02 * std::cos(1.3 * i);
        }
        if (!open) w[static_cast<std::size_t>(n - 1)] = 0.06;  // the hinge offset x
        REQUIRE(dae->calc_residual(0.0, w.data(), wp.data(), w.data() + n_ode, r0.data()));
        int outside = 0, coupled = 0;
        for (int which = 0; which < 2 * size; ++which) {
          const int k = which % size;
          std::vector<double> w1 = w, wp1 = wp;
          (which < size ? w1 : wp1)[static_cast<std::size_t>(k)] += 1e-4;
          REQUIRE(dae->calc_residual(0.0, w1.data(), wp1.data(), w1.data() + n_ode, r1.data()));
          for (int row = 0; row < size; ++row) {
            if (r1[static_cast<std::size_t>(row)] == r0[static_cast<std::size_t>(row)]) continue;
            const int offset = pos[static_cast<std::size_t>(k)] - pos[static_cast<std::size_t>(row)];
            ++coupled;
            if (offset < -lower || offset > upper) {
              ++outside;
              FAIL_CHECK("row " << row << " depends on " << (which < size ? "w_" : "w'_") << k << ": offset " << offset
                                << " outside [" << -lower << ", " << upper << "]");
            }
          }
        }
        CHECK(outside == 0);
        CHECK(coupled > 3 * size);  // the perturbations do reach the residual
      }
}

TEST_CASE("free stack: IDA and the direct bordered solve agree to their tolerances", "[numeric][free][ida]") {
  // Both at rtol 1e-9 (atol 1e-11): each keeps its local error per step below rtol, and the global
  // error of a run builds up over its 2 n phases (restarts, located events): the project's
  // accuracy model allows 20 rtol per phase (stages/energy.hpp), so two solvers may differ by twice
  // that, 40 * 2n rtol = 6.4e-7 relative for n = 8. Measured: at most 30 rtol over rtol 1e-6..1e-10
  // and the three modes (lock times 1e-9 .. 7e-6 relative, scaling with rtol).
  const int n = 8;
  const double rtol = 1e-9, tol = 40.0 * 2 * n * rtol;
  for (const char* mode : {"velocity", "torque", "motor"}) {
    INFO(mode);
    sim::SceneOptions s = slack_scene(mode, n, rtol);
    s.run.integrator = sim::IntegratorKind::dopri54;
    const sim::RunResult d = sim::simulate(s);
    s.run.integrator = sim::IntegratorKind::ida;
    const sim::RunResult a = sim::simulate(s);
    REQUIRE(d.status == sim::RunStatus::ok);
    REQUIRE(a.status == sim::RunStatus::ok);
    REQUIRE(a.bays_completed == n);
    for (int i = 0; i < n; ++i) {
      INFO("bay " << i + 1);
      const auto &bd = d.bays[static_cast<std::size_t>(i)], &ba = a.bays[static_cast<std::size_t>(i)];
      CHECK(ba.entry_time_s == Approx(bd.entry_time_s).epsilon(tol));
      CHECK(ba.lock_time_s == Approx(bd.lock_time_s).epsilon(tol));
      // Impact energies: differences of O(1) energies at the event state; relative to the work.
      CHECK(ba.latch_energy_J == Approx(bd.latch_energy_J).margin(tol * d.drive_work_J));
      CHECK(ba.entry_energy_loss_J == Approx(bd.entry_energy_loss_J).margin(tol * d.drive_work_J));
      CHECK(ba.peak_pin_force_N == Approx(bd.peak_pin_force_N).epsilon(tol));
    }
    CHECK(a.peak_drive_force_N == Approx(d.peak_drive_force_N).epsilon(tol));
    CHECK(a.peak_pin_force_N == Approx(d.peak_pin_force_N).epsilon(tol));
    CHECK(a.drive_work_J == Approx(d.drive_work_J).epsilon(tol));
    // Final state: the history's last row is the end of the run (frame 0 driven, all locked).
    CHECK(a.history.y_driven_m.back() == Approx(d.history.y_driven_m.back()).epsilon(tol));
    CHECK(a.history.driven_speed_m_per_s.back() == Approx(d.history.driven_speed_m_per_s.back()).epsilon(tol));
    CHECK(a.steps > 0);
  }
}

TEST_CASE("free stack rail miss: IDA finds the same closest approach and stop", "[numeric][free][ida]") {
  // paper_free (Table 1, free): rail miss of bay 30 in velocity and motor modes. The closest
  // approach is a refined minimum of a smooth function: it agrees to the solvers' state error.
  const double rtol = 1e-9, tol = 40.0 * 2 * rtol;  // one phase, watched events restart it twice
  for (const char* mode : {"velocity", "motor"}) {
    INFO(mode);
    sim::SceneOptions s;
    s.stack.mode = sim::StackMode::free;
    s.drive.mode = mode_of(mode);
    s.run.rtol = rtol;
    s.run.atol = 1e-2 * rtol;
    s.run.integrator = sim::IntegratorKind::dopri54;
    const sim::RunResult d = sim::simulate(s);
    s.run.integrator = sim::IntegratorKind::ida;
    const sim::RunResult a = sim::simulate(s);
    REQUIRE(d.status == sim::RunStatus::rail_miss);
    REQUIRE(a.status == sim::RunStatus::rail_miss);
    CHECK(a.rail_miss_bay == d.rail_miss_bay);
    CHECK(a.rail_miss_closest_approach_m == Approx(d.rail_miss_closest_approach_m).epsilon(10 * tol));
    CHECK(a.rail_miss_closest_approach_time_s == Approx(d.rail_miss_closest_approach_time_s).epsilon(1e-4));  // flat minimum: t to sqrt(tol)
    CHECK(a.rail_miss_above_rail_top_time_s == Approx(d.rail_miss_above_rail_top_time_s).epsilon(10 * tol));
    CHECK(a.end_time_s == Approx(d.end_time_s).epsilon(10 * tol));
  }
}

TEST_CASE("free stack with IDA: the energy ledger closes at tight tolerance", "[numeric][free][ida]") {
  // As for the direct method (test_free_run.cpp): at rtol 1e-12 the balance W - dT - dU - E_lost
  // stays below 1e-9 of the drive work (measured 7e-11 velocity, 1.6e-10 torque, 9e-11 motor);
  // a missing impact loss would leave 8-25 % of the work.
  for (const char* mode : {"velocity", "torque", "motor"}) {
    INFO(mode);
    sim::SceneOptions s = slack_scene(mode, 8, 1e-12);
    s.run.atol = 1e-14;
    s.run.output_step_s = 0.0;
    s.run.integrator = sim::IntegratorKind::ida;
    const sim::RunResult r = sim::simulate(s);
    REQUIRE(r.status == sim::RunStatus::ok);
    CHECK(r.energy_lost_J > 1e-2 * r.drive_work_J);
    CHECK(std::abs(r.energy_residual_J) < 1e-9 * r.drive_work_J);
    CHECK(r.max_rail_residual_m < 1e-9);
  }
}

TEST_CASE("run.integrator = ida is refused for the held stack", "[unit][ida]") {
  sim::SceneOptions s;
  s.run.integrator = sim::IntegratorKind::ida;
  const std::string e = s.validate();
  CHECK(e.rfind("run.integrator:", 0) == 0);
  s.stack.mode = sim::StackMode::free;
  CHECK(s.validate().empty());
}

TEST_CASE("free stack near a singular end: IDA stops where dopri54 does; no rail margin before any entry",
          "[numeric][free][ida]") {
  // Table 1 with two bays, l_0 = 0.48 m, contacts on: bay 1 (not deploying) straightens during bay
  // 2's stage, before any rail entry. The stop (a bay within 1e-4 l_s of straight) is an event of
  // the state: both solvers find it to their state error at rtol (the time to rtol relative).
  for (const double rtol : {1e-12, 1e-8}) {
    INFO("rtol " << rtol);
    sim::SceneOptions s;
    s.mast.n_bays = 2;
    s.mast.diagonal_free_length_m = 0.48;
    s.stack.mode = sim::StackMode::free;
    s.stack.contacts = sim::StackContacts::on;
    s.run.rtol = rtol;
    s.run.atol = 1e-2 * rtol;
    s.run.integrator = sim::IntegratorKind::dopri54;
    const sim::RunResult d = sim::simulate(s);
    s.run.integrator = sim::IntegratorKind::ida;
    const sim::RunResult a = sim::simulate(s);
    REQUIRE(d.status == sim::RunStatus::singular_configuration);
    INFO(a.message);
    CHECK(a.status == sim::RunStatus::singular_configuration);
    CHECK(a.end_time_s == Approx(d.end_time_s).epsilon(100 * rtol));
    // No bay entered the rail: the margin has no event to measure (docs/model-notes.md "Rail margin").
    CHECK(std::isnan(d.bays[1].entry_time_s));
    CHECK(std::isnan(d.rail_margin_m));
    CHECK(std::isnan(a.rail_margin_m));
  }
}
