// Benchmark (not a test): the free stack (issue 9; docs/model.md §2 "free") on this machine.
//  1. Cost of one right-hand side of phase A and of phase B (the bordered solve) against the
//     number of moving frames, n = 10 .. 1000: median time per evaluation and per frame (the
//     solve is O(n): the time per frame must stay flat).
//  2. Whole slack free-stack deployments (l_0 = 0.49 m, velocity drive, rtol 1e-8) for n = 10 ..
//     1000 bays, stack contacts off and on, medians of repeats side by side. Contacts off, stage j
//     has n - j moving frames (a run is O(n^2)); contacts on, frames resting on the stack are out
//     of the system. Targets of the issue: 30 bays under 50 ms; cost per bay flat within 1.5x.
//  3. Work-precision, n = 10 and 30, every solver (DP5(4), DOP853, CVODE BDF, CVODE Adams, IDA on
//     the residual form), rtol 1e-4 .. 1e-12: largest error of the entry and lock times against a
//     DP5(4) reference at rtol 1e-13, against the median wall time of 5 repeats and the
//     right-hand sides (deterministic: the work apart from the machine's speed).
// Usage: bench_free_stack [--quick | --work-precision]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "bench_timing.hpp"
#include "sim/simulate.hpp"
#include "free_stack/free_phase.hpp"
#include "free_stack/free_phase_b.hpp"

using namespace truss;
using namespace truss::sim;

namespace {
using bench::median;
SceneOptions slack_scene(int n) {
  SceneOptions s;
  s.mast.n_bays = n;
  s.mast.diagonal_free_length_m = 0.49;
  s.stack.mode = StackMode::free;
  s.run.max_wall_time_s = 3600.0;
  return s;
}
double time_runs(const SceneOptions& s, int repeats, RunResult* out) { return bench::time_runs(s, build_mast(s), repeats, out); }
double max_event_error(const RunResult& a, const RunResult& ref) {
  double e = 0.0;
  for (std::size_t i = 0; i < a.bays.size(); ++i) {
    e = std::max(e, std::abs(a.bays[i].lock_time_s - ref.bays[i].lock_time_s));
    e = std::max(e, std::abs(a.bays[i].entry_time_s - ref.bays[i].entry_time_s));
  }
  return e;
}
// Median time of one evaluation of the phase at a spread state (frames 1..n, bay n deploying).
double time_rhs(const stages::PhaseModel& p, int n, int evals) {
  std::vector<double> q(static_cast<std::size_t>(n)), qd(q.size(), 0.01), acc(q.size());
  for (int k = 0; k < n; ++k) q[static_cast<std::size_t>(k)] = 0.001 * (k + 1);
  if (p.context().kind == stages::PhaseKind::on_rail) q.back() = 0.1;  // x on the rail
  stages::PhaseScratch scratch;
  std::vector<double> w;
  for (int rep = 0; rep < 7; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    double sink = 0.0;
    // Two states in turn: a phase answers a state asked again from its last solve.
    for (int i = 0; i < evals; ++i) {
      q[0] = (i & 1) ? 0.001 + 1e-9 : 0.001;
      sink += p.calc_point(q.data(), qd.data(), acc.data(), scratch).drive_force_N;
    }
    w.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / evals);
    if (sink == 12345.678) std::printf(" ");
  }
  return median(w);
}
}  // namespace

void run_cost_tables(bool quick);
void run_work_precision(bool quick);

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const bool wp_only = argc > 1 && std::strcmp(argv[1], "--work-precision") == 0;
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  if (!wp_only) run_cost_tables(quick);
  run_work_precision(quick);
  return 0;
}
void run_cost_tables(bool quick) {
  std::printf("## One right-hand side of the free phases (torque drive)\n\n");
  std::printf("| moving frames | phase A (us) | per frame (ns) | phase B (us) | per frame (ns) |\n|---:|---:|---:|---:|---:|\n");
  for (int n : {10, 30, 100, 300, 1000}) {
    SceneOptions s = slack_scene(n);
    s.drive.mode = model::DriveMode::torque;
    const auto mast = build_mast(s);
    stages::PhaseContext ctx{&mast, stages::PhaseKind::open, n, 0.0, 1.1, 0.36, s.drive, 1.0, 0.0, 1.0};
    const std::vector<model::BayConstants> table = model::calc_bay_table(*ctx.mast);
    const stages::FreePhaseA a(ctx, 1, 0.0, table);
    ctx.kind = stages::PhaseKind::on_rail;
    const stages::FreePhaseB b(ctx, 1, 0.0, 10.0, table);
    const int evals = std::max(200, 200000 / n);
    const double ta = time_rhs(a, n, evals), tb = time_rhs(b, n, evals);
    std::printf("| %d | %.3f | %.1f | %.3f | %.1f |\n", n, 1e6 * ta, 1e9 * ta / n, 1e6 * tb, 1e9 * tb / n);
  }

  std::printf("\n## Slack free-stack deployment (l_0 = 0.49 m, velocity drive, DP5(4), rtol 1e-8), contacts off and on\n\n");
  // Wall times on a shared machine are noisy; the evaluations per bay (deterministic) and the time
  // per evaluation separate the work from the speed of one evaluation.
  std::printf("| bays | off: median (ms) | off: per bay (us) | off: evals per bay | on: median (ms) | on: per bay (us) | "
              "on: evals per bay | on: us per eval | on: lift-offs | status off / on |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  std::vector<int> ns = {10, 30, 100, 300, 1000};
  for (int n : ns) {
    // Contacts off is O(n^2) per run (every frame below the driven one moves): 1000 bays only in
    // the full run. Contacts on: frames resting on the stack are out of the system.
    RunResult off, on;
    double t_off = NAN;
    if (n < 1000 || !quick) t_off = time_runs(slack_scene(n), n <= 30 ? 11 : n <= 100 ? 5 : 1, &off);
    SceneOptions s = slack_scene(n);
    s.stack.contacts = StackContacts::on;
    const double t_on = time_runs(s, n <= 100 ? 11 : n <= 300 ? 5 : 3, &on);
    std::printf("| %d | %.3f | %.2f | %.0f | %.3f | %.2f | %.0f | %.3f | %ld | %s / %s |\n", n, 1e3 * t_off, 1e6 * t_off / n,
                double(off.rhs_evals) / n, 1e3 * t_on, 1e6 * t_on / n, double(on.rhs_evals) / n, 1e6 * t_on / double(on.rhs_evals),
                on.contact_lift_offs, std::isnan(t_off) ? "-" : to_string(off.status), to_string(on.status));
  }

}

void run_work_precision(bool quick) {
  std::printf("\n## Work-precision (slack scene, torque drive 0.002 N m; error: largest entry/lock time error)\n\n");
  std::printf("| bays | integrator | rtol | median wall time (ms) | error (s) | steps | right-hand sides | status |\n|---:|---|---:|---:|---:|---:|---:|---|\n");
  for (int n : {10, 30}) {
    SceneOptions ref_s = slack_scene(n);
    ref_s.drive.mode = model::DriveMode::torque;
    ref_s.drive.torque_Nm = 0.002;
    ref_s.run.rtol = 1e-13;
    ref_s.run.atol = 1e-15;
    RunResult ref;
    time_runs(ref_s, 0, &ref);
    for (auto kind : {integrators::IntegratorKind::dopri54, integrators::IntegratorKind::dop853, integrators::IntegratorKind::cvode,
                      integrators::IntegratorKind::cvode_adams, integrators::IntegratorKind::ida}) {
      for (double rtol : {1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
        SceneOptions s = ref_s;
        s.run.integrator = kind;
        s.run.rtol = rtol;
        s.run.atol = rtol * 1e-2;
        RunResult r;
        const double t = time_runs(s, quick ? 1 : 5, &r);
        std::printf("| %d | %s | %.0e | %.3f | %.2e | %ld | %ld | %s |\n", n, integrators::to_string(kind), rtol, 1e3 * t,
                    max_event_error(r, ref), r.steps, r.rhs_evals, to_string(r.status));
      }
    }
  }
}
