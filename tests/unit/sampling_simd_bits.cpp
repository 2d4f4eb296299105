// The sampling library's per-run loops, written out byte for byte: the uniforms of a Latin hypercube
// (Feistel permutations, strata) and of a Monte Carlo plan, and their normal and lognormal quantiles
// (AS 241 in bulk: the central region and the tails). Linked once with the library as built
// (TRUSS_SIMD_CLONES: also compiled for x86-64-v4) and once with its portable build; ctest
// sampling_simd_bits requires the two outputs to be equal (src/sampling/simd_clones.hpp).
// The plans: 2,000 runs of 184 dimensions (the Table-1 campaign's) and 3,000 of 31 (an odd bit
// count of the permutation's domain), every run; quantiles of normal and lognormal laws, and of
// uniforms pushed to within 1e-300 of 0 and 1 (AS 241's far tails).
#include <cstdio>
#include <cstring>
#include <vector>

#include "sampling/sampling.hpp"

using namespace truss::sampling;

int main() {
  const Distribution normal = Distribution::normal(1.0, 0.0166), lognormal = Distribution::lognormal(0.1, 0.3);
  auto put = [](const std::vector<double>& v) { std::fwrite(v.data(), sizeof(double), v.size(), stdout); };
  for (const auto method : {SamplingMethod::latin_hypercube, SamplingMethod::monte_carlo}) {
    for (const auto& [n, d] : {std::pair<std::int64_t, int>{2000, 184}, std::pair<std::int64_t, int>{3000, 31}}) {
      const SamplePlan plan(method, n, d, 20261121, {});
      std::vector<double> u(static_cast<std::size_t>(d)), x(u.size());
      for (std::int64_t r = 0; r < n; ++r) {
        plan.calc_uniforms(r, u.data());
        put(u);
        normal.calc_quantiles(u.data(), x.data(), u.size());
        put(x);
        lognormal.calc_quantiles(u.data(), x.data(), u.size());
        put(x);
        for (std::size_t i = 0; i < u.size(); ++i) u[i] = i % 2 ? u[i] * 1e-300 : 1.0 - u[i] * 1e-16;
        normal.calc_quantiles(u.data(), x.data(), u.size());
        put(x);
      }
    }
  }
  return std::fflush(stdout) == 0 ? 0 : 1;
}
