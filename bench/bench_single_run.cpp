// Benchmark (not a test): single-run cost on this machine.
//  1. Table-1 velocity deployment (closed form, no histories) for n = 10 .. 1000 bays:
//     median wall time of repeats, and time per bay (cost must be linear in n).
//  2. 30-bay motor deployment: error against a tight-tolerance reference (DP5(4), rtol 1e-13)
//     versus wall time, for the own DP5(4) pair and for CVODE, at several tolerances.
// Usage: bench_single_run [--quick]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "bench_timing.hpp"
#include "sim/simulate.hpp"

using namespace truss::sim;

namespace {
using truss::bench::time_runs;
double max_lock_error(const RunResult& a, const RunResult& ref) {
  double e = std::abs(a.deploy_time_s - ref.deploy_time_s);
  for (std::size_t i = 0; i < a.bays.size(); ++i) {
    e = std::max(e, std::abs(a.bays[i].lock_time_s - ref.bays[i].lock_time_s));
    e = std::max(e, std::abs(a.bays[i].entry_time_s - ref.bays[i].entry_time_s));
  }
  return e;
}
}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int reps = quick ? 5 : 31;

  std::printf("## Table-1 velocity deployment (closed-form kinematics, no time histories)\n\n");
  std::printf("| bays | median wall time (ms) | per bay (us) | evaluations | status |\n|---:|---:|---:|---:|---|\n");
  for (int n : {10, 30, 100, 300, 1000}) {
    SceneOptions s;
    s.mast.n_bays = n;
    const auto mast = build_mast(s);
    RunResult r;
    const double t = time_runs(s, mast, reps, &r);
    std::printf("| %d | %.4f | %.2f | %ld | %s |\n", n, 1e3 * t, 1e6 * t / n, r.rhs_evals, to_string(r.status));
  }

  std::printf("\n## 30-bay motor deployment: error vs wall time\n\n");
  SceneOptions s;
  s.drive.mode = DriveMode::motor;
  s.run.rtol = 1e-13;
  s.run.atol = 1e-15;
  const auto mast = build_mast(s);
  const RunResult ref = simulate(s, mast);
  std::printf("reference: DP5(4) at rtol 1e-13, deploy time %.12f s, status %s\n\n", ref.deploy_time_s, to_string(ref.status));
  std::printf("| integrator | rtol | median wall time (ms) | steps | rhs evals | max event-time error (s) | energy residual / work |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  for (auto integ : {IntegratorKind::dopri54, IntegratorKind::cvode}) {
    for (double rtol : {1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11}) {
      s.run.integrator = integ;
      s.run.rtol = rtol;
      s.run.atol = rtol * 1e-2;
      RunResult r;
      const double t = time_runs(s, mast, quick ? 3 : 9, &r);
      std::printf("| %s | %.0e | %.3f | %ld | %ld | %.2e | %.1e |\n", to_string(integ), rtol, 1e3 * t, r.steps, r.rhs_evals,
                  max_lock_error(r, ref), std::abs(r.energy_residual_J / r.drive_work_J));
    }
  }
  return 0;
}
