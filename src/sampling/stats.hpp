// Statistics of one output column over the usable runs: count, mean, sample standard deviation,
// extremes and the percentiles of /stats, exact (the order statistics themselves, never an
// estimate), computed the way numpy does it so that a reader recomputing them gets the same bits.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

namespace truss::sampling {

// Percentiles of /stats: 1, 5, 50, 95, 99 and 99.865 (the one-sided 3-sigma level).
inline constexpr std::array<double, 6> kStatPercentiles = {1.0, 5.0, 50.0, 95.0, 99.0, 99.865};
inline constexpr std::array<const char*, 6> kStatPercentileNames = {"p1", "p5", "p50", "p95", "p99", "p99_865"};

struct Stats {
  std::int64_t count = 0;                      // values used: finite values of ok runs
  double mean = 0, std = 0, min = 0, max = 0;  // std: sample (ddof = 1); NaN when undefined
  std::array<double, 6> percentiles{};         // kStatPercentiles
};

// Statistics of the finite values among values[i] for which use[i] is true. Percentiles by
// linear interpolation between order statistics (Hyndman-Fan type 7), computed the way
// numpy.percentile does it (index q (n - 1), lerp from the nearer end), so a reader recomputing
// them with numpy gets the same numbers.
Stats calc_stats(const std::vector<double>& values, const std::vector<std::uint8_t>& use);
// The q-th percentile (0..100) of sorted values, as above.
double calc_percentile_sorted(const std::vector<double>& sorted, double q);
// numpy 1.22+ "linear": virtual index h = q/100 (n - 1) between order statistics lo and hi (0-based,
// n > 0); lerp_numpy(a, b, t) = a + t (b - a) for t < 0.5 and b - (1 - t) (b - a) otherwise (exact at
// both ends). The one definition of the interpolation, used by every percentile the tool writes.
struct PercentileIndex {
  std::size_t lo, hi;
  double t;
};
PercentileIndex find_percentile_index(std::size_t n, double q);
double lerp_numpy(double a, double b, double t);

}  // namespace truss::sampling
