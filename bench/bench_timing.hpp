// Timing shared by the benchmarks (not a test): medians of repeated whole runs.
#pragma once
#include <algorithm>
#include <chrono>
#include <utility>
#include <vector>

#include "sim/simulate.hpp"

namespace truss::bench {

// 0 for no samples: a caller that times 0 repeats wants the run's result, not its time.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Median wall time of `repeats` runs; one more runs first and is dropped (it warms the caches).
// The mast is built by the caller, outside the timed region. out: the last run's result.
inline double time_runs(const sim::SceneOptions& s, const model::MastParams& mast, int repeats, sim::RunResult* out = nullptr) {
  std::vector<double> w;
  for (int i = 0; i <= repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    sim::RunResult r = sim::simulate(s, mast);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (i > 0) w.push_back(dt);
    if (out) *out = std::move(r);
  }
  return median(w);
}

}  // namespace truss::bench
