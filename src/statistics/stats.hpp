// Statistics of one output column over the usable runs: count, mean, sample standard deviation,
// extremes and the percentiles of /stats, exact (the order statistics themselves, never an
// estimate), computed the way numpy does it so that a reader recomputing them gets the same bits.
//
//   values used: x_1 .. x_n, the finite values of the rows with use[i] != 0, in row order.
//   mean = x_1 + d,  d = (sum_i (x_i - x_1)) / n          (shifted by the first value: exact for a
//                                                          constant column, no cancellation)
//   std  = sqrt(sum_i (x_i - x_1 - d)^2 / (n - 1))         (ddof = 1; NaN for n < 2)
//   percentile q: h = q/100 (n - 1), lo = floor(h), hi = min(lo + 1, n - 1), t = h - lo, and
//     lerp_numpy(x_(lo), x_(hi), t) between the order statistics x_(k) (0-based): Hyndman & Fan
//     (1996) type 7, numpy.percentile's "linear" method.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace truss::statistics {

// Percentiles of /stats: 1, 5, 50, 95, 99 and 99.865 (the one-sided 3-sigma level).
inline constexpr std::array<double, 6> kStatPercentiles = {1.0, 5.0, 50.0, 95.0, 99.0, 99.865};
inline constexpr std::array<const char*, 6> kStatPercentileNames = {"p1", "p5", "p50", "p95", "p99", "p99_865"};

struct Stats {
  std::int64_t count = 0;                      // values used: finite values of ok runs
  double mean = 0, std = 0, min = 0, max = 0;  // std: sample (ddof = 1); NaN when undefined
  std::array<double, 6> percentiles{};         // kStatPercentiles
};

// Statistics of the finite values among values[i] for which use[i] is true, as above (all NaN
// when there is none).
Stats calc_stats(const std::vector<double>& values, const std::vector<std::uint8_t>& use);
// The q-th percentile (0..100) of sorted values, as above; NaN when empty.
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

// Puts the order statistics of the finite values x[0..n) at ranks r[0..k) (0-based, ascending, each
// < n, repeats allowed) in their places, as a sort would (of -0.0 and +0.0 at a rank, either one);
// x is only reordered. Quickselect (Hoare 1961) with three-way partitions around a median of three,
// each round keeping only the parts that hold a wanted rank; O(n log k) on average. The one routine
// that selects order statistics in this tool.
void select_order_statistics(double* x, std::size_t n, const std::size_t* r, std::size_t k);

}  // namespace truss::statistics
