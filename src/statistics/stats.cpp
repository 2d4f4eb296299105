// Statistics of one column: the equations are in stats.hpp.
#include "statistics/stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace truss::statistics {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One round's partition (select_part) around p: x[0..n)'s values below p to below[...] (which may be
// x itself: a store never passes the value read), those above it to above[...], each in their order;
// returns their counts. Branch-free: which side a value falls on is not predictable.
std::pair<std::size_t, std::size_t> partition3(const double* x, std::size_t n, double p, double* below,
                                               double* above) {
  std::size_t n_below = 0, n_above = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = x[i];
    below[n_below] = v;
    above[n_above] = v;
    n_below += v < p;
    n_above += p < v;
  }
  return {n_below, n_above};
}

// select_order_statistics on x[0..n), whose ranks are base + 0 .. n - 1 of the whole, for the
// ranks [r, r_end) among them. Each round: the median of three values as the pivot p; x rewritten
// as [below p][p ... p][above p]; the part below recursively, the part above in the loop. Short
// parts, runs of unlucky pivots and a zero pivot (its copies may be -0.0 or +0.0 and must keep their
// bits) end in std::sort.
void select_part(double* x, std::size_t n, std::size_t base, const std::size_t* r, const std::size_t* r_end,
                 double* above, int depth) {
  while (r != r_end) {
    const double a = x[n / 4], b = x[n / 2], c = x[3 * n / 4];
    const double p = std::max(std::min(a, b), std::min(std::max(a, b), c));
    if (n <= 16 || depth > 64 || p == 0.0) {
      std::sort(x, x + n);
      return;
    }
    ++depth;
    const auto [n_below, n_above] = partition3(x, n, p, x, above);
    const std::size_t equal_end = n - n_above;
    std::fill(x + n_below, x + equal_end, p);
    std::copy(above, above + n_above, x + equal_end);
    const std::size_t* r_equal = std::lower_bound(r, r_end, base + n_below);
    select_part(x, n_below, base, r, r_equal, above, depth);
    r = std::lower_bound(r_equal, r_end, base + equal_end);
    x += equal_end;
    base += equal_end;
    n = n_above;
  }
}

}  // namespace

void select_order_statistics(double* x, std::size_t n, const std::size_t* r, std::size_t k) {
  std::vector<double> above(n);
  select_part(x, n, 0, r, r + k, above.data(), 0);
}

PercentileIndex find_percentile_index(std::size_t n, double q) {
  const double h = (q / 100.0) * static_cast<double>(n - 1);
  const double fl = std::floor(h);
  const auto lo = static_cast<std::size_t>(fl);
  return {lo, std::min(lo + 1, n - 1), h - fl};
}

double lerp_numpy(double a, double b, double t) {
  const double d = b - a;
  return t >= 0.5 ? b - d * (1.0 - t) : a + d * t;
}

double calc_percentile_sorted(const std::vector<double>& x, double q) {
  if (x.empty()) return kNaN;
  const PercentileIndex p = find_percentile_index(x.size(), q);
  return lerp_numpy(x[p.lo], x[p.hi], p.t);
}

Stats calc_stats(const std::vector<double>& values, const std::vector<std::uint8_t>& use) {
  std::vector<double> x;
  x.reserve(values.size());
  for (std::size_t i = 0; i < values.size(); ++i)
    if (use[i] && std::isfinite(values[i])) x.push_back(values[i]);
  Stats s;
  s.count = static_cast<std::int64_t>(x.size());
  if (x.empty()) {
    s.mean = s.std = s.min = s.max = kNaN;
    s.percentiles.fill(kNaN);
    return s;
  }
  const double x0 = x.front();
  double sum = 0.0;
  for (double v : x) sum += v - x0;
  const double dm = sum / static_cast<double>(x.size());
  s.mean = x0 + dm;
  double ss = 0.0;
  for (double v : x) ss += (v - x0 - dm) * (v - x0 - dm);
  s.std = x.size() > 1 ? std::sqrt(ss / static_cast<double>(x.size() - 1)) : kNaN;
  // The extremes and the two order statistics of each percentile, selected together.
  const std::size_t n = x.size();
  std::array<PercentileIndex, kStatPercentiles.size()> idx{};
  std::vector<std::size_t> ranks = {0, n - 1};
  for (std::size_t k = 0; k < kStatPercentiles.size(); ++k) {
    idx[k] = find_percentile_index(n, kStatPercentiles[k]);
    ranks.push_back(idx[k].lo);
    ranks.push_back(idx[k].hi);
  }
  std::sort(ranks.begin(), ranks.end());
  select_order_statistics(x.data(), n, ranks.data(), ranks.size());
  s.min = x.front();
  s.max = x.back();
  for (std::size_t k = 0; k < kStatPercentiles.size(); ++k)
    s.percentiles[k] = lerp_numpy(x[idx[k].lo], x[idx[k].hi], idx[k].t);
  return s;
}

}  // namespace truss::statistics
