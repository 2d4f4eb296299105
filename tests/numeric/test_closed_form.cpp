// The velocity mode's closed form (stages/phase_kinematic.hpp, stages/closed_form_peaks.hpp):
//   - the peak search on samples with exact derivatives, against functions whose maxima are known;
//   - the drive work of every phase (the change of mechanical energy between its end points)
//     against an independent quadrature of F dy_m along the phase, in another parametrization;
//   - the reported peak times against the roots of the load's derivative found independently:
//     bisection on the sign of a central difference of the closed form in long double.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <vector>

#include "model/rail.hpp"
#include "numerics/gauss_kronrod.hpp"
#include "sim/simulate.hpp"
#include "stages/closed_form_peaks.hpp"
#include "stages/energy.hpp"
#include "stages/held_phase.hpp"
#include "stages/stage_plan.hpp"
#include "test_helpers.hpp"

using namespace truss;
using namespace truss::sim;
using stages::kForce;
using stages::PeakSearch;
using stages::RatedSample;

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Samples of Q(t) (as the drive force) with Q'(t) at the given times; eval counts its calls.
template <class Q, class DQ>
struct AnalyticLoad {
  Q q;
  DQ dq;
  int evals = 0;
  RatedSample operator()(double t) {
    ++evals;
    RatedSample s;
    s.t = t;
    s.q[kForce] = q(t);
    s.dq[kForce] = dq(t);
    return s;
  }
};
// clang 14 (the sanitizer build) has no deduction for aggregates (P1816); GCC 12 has.
template <class Q, class DQ>
AnalyticLoad(Q, DQ) -> AnalyticLoad<Q, DQ>;

std::array<PeakSearch, stages::kQuantityCount> force_only() {
  std::array<PeakSearch, stages::kQuantityCount> s;
  s.fill(PeakSearch::none);
  s[kForce] = PeakSearch::full;
  return s;
}

template <class Load>
stages::Extremum find_peak(Load& load, const std::vector<double>& times, double tie_tol = 0.0) {
  stages::RatedPeakWork work;
  for (double t : times) work.samples.push_back(load(t));
  stages::PeakTracker tr;
  tr.set_tie_tolerance(tie_tol);
  tr.start_stage(3);
  load.evals = 0;
  stages::absorb_rated_peaks(work, tr, load, force_only());
  return tr.stage_force;
}

}  // namespace

TEST_CASE("closed-form peaks: an interior maximum is the root of Q', to the rounding of t", "[closed_form][peaks]") {
  // Q = 2 + sin(3 t + 0.4): maximum 3 at t* = (pi/2 - 0.4) / 3 = 0.3902654, between samples 1/3 apart.
  AnalyticLoad load{[](double t) { return 2.0 + std::sin(3.0 * t + 0.4); },
                    [](double t) { return 3.0 * std::cos(3.0 * t + 0.4); }};
  const stages::Extremum e = find_peak(load, {0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0});
  const double t_star = (M_PI / 2 - 0.4) / 3.0;
  CHECK(e.value == Approx(3.0).epsilon(4 * kEps));
  CHECK(std::abs(e.t - t_star) < 8 * kEps);  // a search on values finds t only to sqrt(eps): ~1e-8
  CHECK(e.bay == 3);
  CHECK(load.evals <= 5);  // a secant from the Hermite estimate converges superlinearly
}

TEST_CASE("closed-form peaks: a maximum hidden between two falling slopes is found", "[closed_form][peaks]") {
  // Q' = -(t - 0.1)(t - 0.9): falling at both samples t = 0 and 1, a minimum at 0.1 and the
  // maximum at t = 0.9, Q(0.9) = 0.081 above Q(0) = 0 and Q(1) = 0.0767 (cubic: Hermite is exact).
  AnalyticLoad load{[](double t) { return -(t * t * t / 3.0 - 0.5 * t * t + 0.09 * t); },
                    [](double t) { return -(t - 0.1) * (t - 0.9); }};
  const stages::Extremum e = find_peak(load, {0.0, 1.0});
  CHECK(e.t == Approx(0.9).epsilon(8 * kEps));
  CHECK(e.value == Approx(0.081).epsilon(8 * kEps));
}

TEST_CASE("closed-form peaks: a maximum at a sample or a phase end is the sample; rounding is no maximum",
          "[closed_form][peaks]") {
  // Rising to the end: the last sample, no refinement.
  AnalyticLoad rising{[](double t) { return t * t; }, [](double t) { return 2.0 * t; }};
  stages::Extremum e = find_peak(rising, {0.0, 0.5, 1.0});
  CHECK(e.value == 1.0);
  CHECK(e.t == 1.0);
  CHECK(rising.evals == 0);
  // A prescribed value whose samples differ by rounding and whose slopes are rounding noise.
  AnalyticLoad flat{[](double t) { return 0.1 * (1.0 + (t > 0.4 && t < 0.6 ? kEps : 0.0)); },
                    [](double t) { return t < 0.5 ? 1e-17 : -1e-17; }};
  e = find_peak(flat, {0.0, 0.25, 0.5, 0.75, 1.0});
  CHECK(flat.evals == 0);
  CHECK(e.t == 0.5);
  // Equal maxima: the earliest (docs/model.md §5).
  AnalyticLoad twin{[](double t) { return std::cos(2.0 * M_PI * t); },
                    [](double t) { return -2.0 * M_PI * std::sin(2.0 * M_PI * t); }};
  e = find_peak(twin, {0.0, 0.25, 0.5, 0.75, 1.0});
  CHECK(e.t == 0.0);
  CHECK(e.value == 1.0);
}

TEST_CASE("closed-form peaks: equal maxima in a phase are one peak, at the earliest", "[closed_form][peaks]") {
  // Q = sin(2 pi t) + 1e-7 t over [0, 2]: maxima at t = 1/4 and 5/4, the later higher by 1e-7.
  // Within a tie tolerance of 1e-5 they are one peak: the larger value at the earlier time; with
  // no tolerance the later, higher one.
  AnalyticLoad load{[](double t) { return std::sin(2.0 * M_PI * t) + 1e-7 * t; },
                    [](double t) { return 2.0 * M_PI * std::cos(2.0 * M_PI * t) + 1e-7; }};
  const std::vector<double> times{0.0, 0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 1.05, 1.2, 1.35, 1.5, 1.65, 1.8, 1.95, 2.0};
  const double t1 = std::acos(-1e-7 / (2.0 * M_PI)) / (2.0 * M_PI), t2 = t1 + 1.0;  // Q' = 0
  stages::Extremum e = find_peak(load, times, 1e-5);
  CHECK(e.t == Approx(t1).margin(1e-14));
  CHECK(e.value == Approx(std::sin(2.0 * M_PI * t2) + 1e-7 * t2).epsilon(4 * kEps));
  e = find_peak(load, times, 0.0);
  CHECK(e.t == Approx(t2).margin(1e-14));
}

namespace {

// The smooth drive work of each phase of a held velocity run by adaptive Gauss-Kronrod on F dy_m:
// open phases in y_m, rail phases in x with dy_m = Y'(x) dx (the solver works in time, from the
// remaining travel). Independent of the energies the solver uses.
double calc_quadrature_work_J(const SceneOptions& s, const model::MastParams& mast) {
  std::vector<stages::StageSpec> plan;
  const double dir = model::calc_direction_sign(s.run.direction);
  REQUIRE(stages::plan_held_stages(mast, dir, plan).empty());
  const model::RailConstants rail = model::calc_rail_constants(mast.rail);
  const double v = s.drive.speed_m_per_s;
  double W = 0.0;
  for (const stages::StageSpec& st : plan) {
    for (const stages::PhaseSpec& ph : st.phases) {
      stages::PhaseContext ctx{&mast, ph.kind, st.bay, ph.lower_held_height_m, st.locked_mass_kg, st.panel_height_offset_m,
                               s.drive, dir, ph.q_end, ph.q_end > ph.q_start ? 1.0 : -1.0};
      const stages::HeldPhase phase(ctx);
      const double l = mast.bay(st.bay).strut_length_m;
      auto dW = [&](double q) {
        if (ph.kind == stages::PhaseKind::open) return phase.calc_point(q, dir * v).drive_force_N;
        const double dY = model::calc_on_rail(rail, l, q).dY;
        return phase.calc_point(q, dir * v / dY).drive_force_N * dY;
      };
      W += numerics::integrate_gk15(dW, ph.q_start, ph.q_end, 1e-15);
    }
  }
  return W;
}

}  // namespace

TEST_CASE("velocity mode: each phase's drive work is its energy change, as a quadrature of F dy_m confirms",
          "[closed_form][energy]") {
  // In velocity mode the rail (ideal) and the held frames (at rest) do no work: over a smooth
  // phase W = dT + dU of the moving bays, which the solver reports. A quadrature of the inverse-
  // dynamics force over the same path must give it to its own tolerance (1e-15 J a piece, kinks
  // bisected), here bounded by 1e-12 of the work: a force inconsistent with the energies fails.
  struct Case { int n; model::Direction dir; bool panels; double k_N_per_m; };
  for (const Case& c : {Case{5, model::Direction::deploy, false, 20.0}, Case{5, model::Direction::retract, true, 20.0},
                        Case{3, model::Direction::deploy, true, 300.0}, Case{4, model::Direction::retract, false, 2.0}}) {
    SceneOptions s;
    s.mast.n_bays = c.n;
    s.mast.diagonal_stiffness_N_per_m = c.k_N_per_m;
    s.run.direction = c.dir;
    if (c.panels) { s.panels.count = 40; s.panels.length_m = 0.5; s.panels.mass_kg = 0.05; }
    const model::MastParams mast = build_mast(s);
    const RunResult r = simulate(s, mast);
    REQUIRE(r.status == RunStatus::ok);
    const double W = calc_quadrature_work_J(s, mast);
    INFO("n " << c.n << " dir " << to_string(c.dir) << " panels " << c.panels << ": energies " << r.drive_work_smooth_J
              << " J, quadrature " << W << " J");
    CHECK(std::abs(r.drive_work_smooth_J - W) <= 1e-12 * std::abs(W));
    CHECK(std::abs(r.energy_residual_J) <= 1e-13 * stages::calc_energy_scale_J(r));
  }
}

TEST_CASE("velocity mode: peak pin-force times are the roots of its derivative (long-double bisection)",
          "[closed_form][peaks]") {
  // The pin force of bay m peaks inside its rail phase. Independent of the solver's dual numbers,
  // Hermite estimate and secant: bisection on the sign of a central difference of the closed form
  // evaluated in long double (rounding 1e-19); that root is good to about 1e-13 s (bays 2-4 of
  // Table 1 repeat one motion 3.6 s apart). The reported time must lie within 1e-12 s of it (a
  // search on values, as before, was off by 4e-9 to 4e-8 s here).
  for (auto dir : {model::Direction::deploy, model::Direction::retract}) {
    SceneOptions s;
    s.mast.n_bays = 4;
    s.run.direction = dir;
    const model::MastParams mast = build_mast(s);
    const RunResult r = simulate(s, mast);
    REQUIRE(r.status == RunStatus::ok);
    std::vector<stages::StageSpec> plan;
    const double d = model::calc_direction_sign(dir), v = s.drive.speed_m_per_s;
    REQUIRE(stages::plan_held_stages(mast, d, plan).empty());
    const model::RailConstants rail = model::calc_rail_constants(mast.rail);
    for (const stages::StageSpec& st : plan) {
      const stages::BayResult& b = r.bays[static_cast<std::size_t>(st.bay - 1)];
      const stages::PhaseSpec& ph = st.phases[d > 0 ? 1 : 0];
      stages::PhaseContext ctx{&mast, ph.kind, st.bay, ph.lower_held_height_m, st.locked_mass_kg, st.panel_height_offset_m,
                               s.drive, d, ph.q_end, ph.q_end > ph.q_start ? 1.0 : -1.0};
      const stages::HeldPhase phase(ctx);
      const double l = mast.bay(st.bay).strut_length_m;
      // Rail phase: deploy from entry to the lock (travel v (t_lock - t)), retract from the unlock.
      const long double t_lock = b.lock_time_s;
      auto pin = [&](long double t) {
        const long double e = d > 0 ? v * (t_lock - t) : v * (t - t_lock);
        return phase.calc_point_at_speed_t(model::calc_x_on_rail_from_travel(rail, l, e), d * v).pin_force_N;
      };
      // Fourth-order central difference, h = 1e-5 s: truncation h^4 Q^(5) / 30 and rounding
      // 1e-19 Q / h both move the sign change by far less than 1e-14 s.
      const long double h = 1e-5L;
      auto slope = [&](long double t) {
        return (8.0L * (pin(t + h) - pin(t - h)) - (pin(t + 2 * h) - pin(t - 2 * h))) / (12.0L * h);
      };
      long double lo = b.peak_pin_force_time_s - 1e-4, hi = b.peak_pin_force_time_s + 1e-4;
      REQUIRE(slope(lo) > 0.0L);
      REQUIRE(slope(hi) < 0.0L);
      for (int i = 0; i < 80; ++i) (slope(0.5L * (lo + hi)) > 0.0L ? lo : hi) = 0.5L * (lo + hi);
      const double t_root = static_cast<double>(0.5L * (lo + hi));
      INFO(to_string(dir) << " bay " << st.bay << ": reported " << fmt::format("{:.17g}", b.peak_pin_force_time_s) << " s, root "
                          << fmt::format("{:.17g}", t_root) << " s");
      CHECK(std::abs(b.peak_pin_force_time_s - t_root) < 1e-12);
      CHECK(b.peak_pin_force_N == Approx(static_cast<double>(pin(t_root))).epsilon(1e-13));
    }
  }
}

TEST_CASE("velocity mode: the Table-1 deployment evaluates its closed form fewer than 40 times a bay",
          "[closed_form][cost]") {
  // A grid of 4 samples a smooth piece, the kink's one-sided slope, and a few secant steps per
  // interior peak: about 15 a bay. Histories off: nothing else is computed.
  SceneOptions s;
  s.mast.n_bays = 30;
  const RunResult r = simulate(s);
  REQUIRE(r.status == RunStatus::ok);
  CHECK(r.rhs_evals < 40 * 30);
  CHECK(r.rhs_evals > 0);
}
