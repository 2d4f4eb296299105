// Benchmark (not a test): the sampling library's per-run loops as a campaign's ranks pay them, the
// uniforms of a Latin hypercube of N runs and D dimensions (the Table-1 campaign: 10,000 x 184)
// and their normal quantiles in bulk, and the same quantiles one value at a time (calc_quantile, the
// reference the bulk path must match bit for bit; the difference is what the bulk path pays). Built twice: bench_uniforms with the library as built
// (TRUSS_SIMD_CLONES: also compiled for x86-64-v4), bench_uniforms_portable with its portable
// build; run them in turn. Wall time per run, medians of REPEATS passes over all runs.
//   bench_uniforms [N=10000] [D=184] [REPEATS=7]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "sampling/sampling.hpp"

using namespace truss::sampling;

int main(int argc, char** argv) {
  const std::int64_t n = argc > 1 ? std::atoll(argv[1]) : 10000;
  const int d = argc > 2 ? std::atoi(argv[2]) : 184, repeats = argc > 3 ? std::atoi(argv[3]) : 7;
  const SamplePlan plan(SamplingMethod::latin_hypercube, n, d, 20261121, {});
  const Distribution normal = Distribution::normal(1.0, 0.0166);
  std::vector<double> u(static_cast<std::size_t>(d)), x(u.size()), t_u, t_q, t_one;
  double sink = 0.0;
  for (int rep = 0; rep < repeats; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::int64_t r = 0; r < n; ++r) {
      plan.calc_uniforms(r, u.data());
      sink += u[0];
    }
    const auto t1 = std::chrono::steady_clock::now();
    for (std::int64_t r = 0; r < n; ++r) {
      plan.calc_uniforms(r, u.data());
      normal.calc_quantiles(u.data(), x.data(), u.size());
      sink += x[0];
    }
    const auto t2 = std::chrono::steady_clock::now();
    for (std::int64_t r = 0; r < n; ++r) {
      plan.calc_uniforms(r, u.data());
      for (std::size_t i = 0; i < u.size(); ++i) x[i] = normal.calc_quantile(u[i]);
      sink += x[0];
    }
    const auto t3 = std::chrono::steady_clock::now();
    const double a = std::chrono::duration<double>(t1 - t0).count(), b = std::chrono::duration<double>(t2 - t1).count(),
                 c = std::chrono::duration<double>(t3 - t2).count();
    t_u.push_back(a / static_cast<double>(n) * 1e6);
    t_q.push_back((b - a) / static_cast<double>(n) * 1e6);
    t_one.push_back((c - a) / static_cast<double>(n) * 1e6);
  }
  std::sort(t_u.begin(), t_u.end());
  std::sort(t_q.begin(), t_q.end());
  std::sort(t_one.begin(), t_one.end());
  std::printf("%lld runs, %d dimensions, %d repeats (medians): uniforms %.2f us a run, their normal quantiles "
              "%.2f us a run in bulk, %.2f us a run one at a time (checksum %.6g)\n",
              static_cast<long long>(n), d, repeats, t_u[t_u.size() / 2], t_q[t_q.size() / 2],
              t_one[t_one.size() / 2], sink);
  return 0;
}
