// Statistics of one column: the equations are in stats.hpp.
#include "sampling/stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace truss::sampling {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Puts the order statistics ks[k] (sorted, all in [lo, hi)) of x[lo, hi) in place.
void multi_select(std::vector<double>& x, std::size_t lo, std::size_t hi, const std::size_t* k0,
                  const std::size_t* k1) {
  if (k0 == k1 || hi - lo < 2) return;
  const std::size_t* mid = k0 + (k1 - k0) / 2;
  std::nth_element(x.begin() + static_cast<std::ptrdiff_t>(lo), x.begin() + static_cast<std::ptrdiff_t>(*mid),
                   x.begin() + static_cast<std::ptrdiff_t>(hi));
  multi_select(x, lo, *mid, k0, mid);
  multi_select(x, *mid + 1, hi, mid + 1, k1);
}

// Order-preserving unsigned key of a finite double (negative: all bits flipped; positive: sign set).
std::uint64_t order_key(double v) {
  std::uint64_t u = 0;
  std::memcpy(&u, &v, 8);
  return (u >> 63) ? ~u : (u | (std::uint64_t{1} << 63));
}

// The order statistics ks (sorted, distinct) of x, in place as multi_select leaves them, for large
// x by one bucketing pass: the keys' range is cut into 4096 buckets, a histogram finds the bucket
// (and rank in it) of each wanted order statistic, one more pass collects the values of those few
// buckets, and each is selected there. Three linear passes instead of log(k) rounds of nth_element;
// the values found are the same order statistics. Returns them in the order of ks.
std::vector<double> select_order_stats(std::vector<double>& x, const std::vector<std::size_t>& ks) {
  constexpr int kBits = 12;
  std::uint64_t lo = ~std::uint64_t{0}, hi = 0;
  for (double v : x) {
    const std::uint64_t k = order_key(v);
    lo = std::min(lo, k);
    hi = std::max(hi, k);
  }
  int shift = 0;
  while (((hi - lo) >> shift) >= (std::uint64_t{1} << kBits)) ++shift;
  std::vector<std::size_t> count((std::size_t{1} << kBits) + 1, 0);
  for (double v : x) ++count[static_cast<std::size_t>((order_key(v) - lo) >> shift)];
  // Bucket of each wanted rank and the rank inside it.
  std::vector<std::int16_t> slot(count.size(), -1);
  std::vector<std::size_t> bucket_of(ks.size()), first_of(ks.size());
  std::vector<std::vector<double>> cand;
  std::size_t below = 0, b = 0;
  for (std::size_t j = 0; j < ks.size(); ++j) {
    while (below + count[b] <= ks[j]) below += count[b++];
    bucket_of[j] = b;
    first_of[j] = below;
    if (slot[b] < 0) {
      slot[b] = static_cast<std::int16_t>(cand.size());
      cand.emplace_back().reserve(count[b]);
    }
  }
  for (double v : x) {
    const std::int16_t s = slot[static_cast<std::size_t>((order_key(v) - lo) >> shift)];
    if (s >= 0) cand[static_cast<std::size_t>(s)].push_back(v);
  }
  std::vector<double> out(ks.size());
  for (std::size_t j = 0; j < ks.size(); ++j) {
    auto& c = cand[static_cast<std::size_t>(slot[bucket_of[j]])];
    const auto r = static_cast<std::ptrdiff_t>(ks[j] - first_of[j]);
    std::nth_element(c.begin(), c.begin() + r, c.end());
    out[j] = c[static_cast<std::size_t>(r)];
  }
  return out;
}

}  // namespace

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
  // Shifted by the first value: exact for a constant column (std 0, not rounding noise) and
  // free of cancellation when the spread is tiny against the mean.
  const double x0 = x.front();
  double sum = 0.0;
  for (double v : x) sum += v - x0;
  const double dm = sum / static_cast<double>(x.size());
  s.mean = x0 + dm;
  double ss = 0.0;
  for (double v : x) ss += (v - x0 - dm) * (v - x0 - dm);
  s.std = x.size() > 1 ? std::sqrt(ss / static_cast<double>(x.size() - 1)) : kNaN;
  // Only a dozen order statistics are needed: multi-select them (select the middle one, then
  // recurse on both sides), O(n log k) instead of a full O(n log n) sort.
  const std::size_t n = x.size();
  std::array<PercentileIndex, kStatPercentiles.size()> idx{};
  std::vector<std::size_t> ks = {0, n - 1};
  for (std::size_t k = 0; k < kStatPercentiles.size(); ++k) {
    idx[k] = find_percentile_index(n, kStatPercentiles[k]);
    ks.push_back(idx[k].lo);
    ks.push_back(idx[k].hi);
  }
  std::sort(ks.begin(), ks.end());
  ks.erase(std::unique(ks.begin(), ks.end()), ks.end());
  auto at = [&](std::size_t k) { return x[k]; };
  if (n < (std::size_t{1} << 14)) {
    multi_select(x, 0, n, ks.data(), ks.data() + ks.size());
    s.min = x.front();
    s.max = x.back();
    for (std::size_t k = 0; k < kStatPercentiles.size(); ++k)
      s.percentiles[k] = lerp_numpy(at(idx[k].lo), at(idx[k].hi), idx[k].t);
    return s;
  }
  // Large columns: the order statistics by bucketing (same values, fewer passes).
  const std::vector<double> v = select_order_stats(x, ks);
  auto stat = [&](std::size_t k) {
    return v[static_cast<std::size_t>(std::lower_bound(ks.begin(), ks.end(), k) - ks.begin())];
  };
  s.min = stat(0);
  s.max = stat(n - 1);
  for (std::size_t k = 0; k < kStatPercentiles.size(); ++k)
    s.percentiles[k] = lerp_numpy(stat(idx[k].lo), stat(idx[k].hi), idx[k].t);
  return s;
}

}  // namespace truss::sampling
