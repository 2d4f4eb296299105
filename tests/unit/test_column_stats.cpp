// Statistics of a column (statistics/stats: calc_stats, the one selection of order statistics) against
// sorted values and hand-computed figures; streamed column statistics (statistics/column_stats)
// against calc_stats on the whole column: chunks completing in any order, summaries made against
// windows that have narrowed since, ties, unusable rows; a drifting column must come back
// unresolved, never wrong.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "statistics/column_stats.hpp"
#include "statistics/stats.hpp"

using namespace truss::statistics;

namespace {

struct Streamed {
  Stats stats;
  bool resolved = false;
  std::size_t peak_kept = 0;
};

// Feeds `v` (use: ok rows) in chunks of `rows`, completing in a shuffled order; each summary is
// made when its chunk completes but merged up to `lag` completions later, against the windows of
// the moment it was made (which may have narrowed since).
Streamed stream(const std::vector<double>& v, const std::vector<std::uint8_t>& use, std::size_t rows, std::size_t lag,
                std::mt19937_64& rng) {
  const std::size_t n_chunks = (v.size() + rows - 1) / rows;
  std::vector<std::size_t> order(n_chunks);
  for (std::size_t i = 0; i < n_chunks; ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  ColumnStats cs;
  std::deque<std::pair<std::size_t, ChunkSummary>> in_flight;
  Streamed out;
  auto merge_one = [&] {
    const std::size_t k = rng() % in_flight.size();
    cs.add(static_cast<std::int64_t>(in_flight[k].first), std::move(in_flight[k].second));
    in_flight.erase(in_flight.begin() + static_cast<std::ptrdiff_t>(k));
    out.peak_kept = std::max(out.peak_kept, cs.kept_values());
  };
  for (std::size_t c : order) {
    const std::size_t first = c * rows, r = std::min(rows, v.size() - first);
    const char* bytes = reinterpret_cast<const char*>(v.data() + first);
    if (!cs.seeded()) cs.seed(bytes, r, 1, use.data() + first);
    in_flight.emplace_back(c, calc_chunk_summary(bytes, r, 1, use.data() + first, cs.windows()));
    while (in_flight.size() > lag) merge_one();
  }
  while (!in_flight.empty()) merge_one();
  CHECK(cs.complete(static_cast<std::int64_t>(n_chunks)));
  CHECK_FALSE(cs.complete(static_cast<std::int64_t>(n_chunks) + 1));
  out.stats = cs.calc_stats(out.resolved);
  return out;
}

void check_equal(const Stats& s, const Stats& ref, bool percentiles) {
  CHECK(s.count == ref.count);
  CHECK(s.min == ref.min);
  CHECK(s.max == ref.max);
  // Moments: the same sums in another grouping (per chunk, combined by Chan's update). Both
  // round by about sqrt(n) eps max|v| (at most n eps max|v|): 1e-12 max|v| is a hundred times
  // that for n = 2e5 and also covers a mean that cancels between signs.
  const double scale = std::max(std::abs(ref.min), std::abs(ref.max));
  CHECK(s.mean == Approx(ref.mean).epsilon(1e-13).margin(1e-12 * scale));
  if (ref.count > 1) CHECK(s.std == Approx(ref.std).epsilon(1e-10).margin(1e-12 * scale));
  if (percentiles)
    for (std::size_t k = 0; k < kStatTargets; ++k) {
      INFO("percentile " << kStatPercentiles[k]);
      CHECK(s.percentiles[k] == ref.percentiles[k]);  // the same order statistics, the same lerp
    }
}

}  // namespace

TEST_CASE("streamed statistics: exact percentiles of the whole column, any order of completion", "[campaign][stats]") {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(1.25, 0.01);
  const std::size_t n = 200000;
  std::vector<std::vector<double>> columns(5, std::vector<double>(n));
  std::vector<std::uint8_t> use(n);
  for (std::size_t i = 0; i < n; ++i) {
    use[i] = rng() % 10 != 0;                                              // 10 % failed runs
    columns[0][i] = g(rng);                                                // a load: narrow spread
    columns[1][i] = static_cast<double>(rng() % 3) - 1.0;                  // heavy ties: -1, 0, 1
    columns[2][i] = 4.5;                                                   // constant
    columns[3][i] = (rng() % 2 ? 1.0 : -1.0) * std::exp(10 * g(rng));      // both signs, wide range
    columns[4][i] = i % 997 == 5 ? std::numeric_limits<double>::quiet_NaN() : std::round(g(rng) * 1e4);  // NaN, discrete
  }
  for (std::size_t c = 0; c < columns.size(); ++c)
    for (std::size_t lag : {std::size_t{0}, std::size_t{7}}) {
      INFO("column " << c << ", lag " << lag);
      const Streamed s = stream(columns[c], use, 4096, lag, rng);
      CHECK(s.resolved);
      check_equal(s.stats, calc_stats(columns[c], use), true);
      // Kept values grow as sqrt(N): at 180,000 usable values, at most about 3 w + 1024 a target
      // (w = 6 sqrt(N p (1 - p)) + 64): well under a tenth of the column.
      CHECK(s.peak_kept < n / 10);
    }
}

TEST_CASE("streamed statistics: small and empty columns", "[campaign][stats]") {
  std::mt19937_64 rng(3);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> v = {4.0, 100.0, 1.0, nan, 10.0, 2.0};
  const std::vector<std::uint8_t> use = {1, 0, 1, 1, 1, 1};
  for (std::size_t rows : {std::size_t{1}, std::size_t{2}, std::size_t{6}}) {
    const Streamed s = stream(v, use, rows, 2, rng);
    CHECK(s.resolved);
    check_equal(s.stats, calc_stats(v, use), true);
  }
  const Streamed none = stream({nan, 3.0}, {1, 0}, 1, 0, rng);
  CHECK(none.stats.count == 0);
  CHECK(std::isnan(none.stats.mean));
  CHECK(std::isnan(none.stats.percentiles[2]));
  const Streamed one = stream({3.0}, {1}, 1, 0, rng);
  CHECK(one.stats.percentiles[0] == 3.0);
  CHECK(std::isnan(one.stats.std));
}

TEST_CASE("streamed statistics: the first windows are the order statistics of a whole chunk", "[campaign][stats]") {
  // The rule of column_stats.hpp from sorted values: for target p among the chunk's n usable values,
  // r = p (n - 1), w = ceil(6 sqrt(n p (1 - p))) + 16, the window [x_(floor r - w), x_(ceil r + w)],
  // an end past the values left open. Every row counts (no sample): rows past 2,048 included, a
  // stride, unused rows, NaN; a chunk with both zeros among ties.
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  const double inf = std::numeric_limits<double>::infinity();
  for (const std::size_t rows : {std::size_t{4096}, std::size_t{3000}, std::size_t{40}}) {
    for (int kind = 0; kind < 2; ++kind) {
      std::vector<double> v(2 * rows, 1e300);
      std::vector<std::uint8_t> use(rows);
      std::vector<double> x;
      for (std::size_t i = 0; i < rows; ++i) {
        double a = kind == 0 ? g(rng) : static_cast<double>(static_cast<int>(rng() % 5) - 2) * 0.0;
        if (i % 97 == 3) a = std::numeric_limits<double>::quiet_NaN();
        v[2 * i] = i < rows / 2 ? a : a + 10.0;  // the second half apart: a sample would miss it
        use[i] = rng() % 9 != 0;
        if (use[i] && std::isfinite(v[2 * i])) x.push_back(v[2 * i]);
      }
      std::sort(x.begin(), x.end());
      const auto n = static_cast<std::int64_t>(x.size());
      const Windows w = calc_first_windows(reinterpret_cast<const char*>(v.data()), rows, 2, use.data());
      for (std::size_t t = 0; t < kStatTargets; ++t) {
        INFO("rows " << rows << ", kind " << kind << ", percentile " << kStatPercentiles[t]);
        const double p = kStatPercentiles[t] / 100.0, r = p * static_cast<double>(n - 1);
        const auto half = static_cast<std::int64_t>(std::ceil(6.0 * std::sqrt(static_cast<double>(n) * p * (1.0 - p)))) + 16;
        const auto lo = static_cast<std::int64_t>(std::floor(r)) - half, hi = static_cast<std::int64_t>(std::ceil(r)) + half;
        CHECK(w[t].lo == (lo > 0 ? x[static_cast<std::size_t>(lo)] : -inf));
        CHECK(w[t].hi == (hi < n - 1 ? x[static_cast<std::size_t>(hi)] : inf));
      }
    }
  }
}

TEST_CASE("streamed statistics: a column that drifts with the run index comes back unresolved, not wrong", "[campaign][stats]") {
  // Sorted values completing in index order: the first chunk's windows hold the lowest values only.
  const std::size_t n = 100000;
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<double>(i) * 0.5;
  const std::vector<std::uint8_t> use(n, 1);
  ColumnStats cs;
  const char* bytes = reinterpret_cast<const char*>(v.data());
  cs.seed(bytes, 1000, 1, use.data());
  std::size_t peak = 0;
  for (std::size_t c = 0; c < n / 1000; ++c) {
    cs.add(static_cast<std::int64_t>(c), calc_chunk_summary(bytes + 8000 * c, 1000, 1, use.data(), cs.windows()));
    peak = std::max(peak, cs.kept_values());
  }
  bool resolved = true;
  const Stats s = cs.calc_stats(resolved);
  const Stats ref = calc_stats(v, use);
  CHECK_FALSE(resolved);
  CHECK(peak < n / 4);  // given-up targets keep nothing
  check_equal(s, ref, false);
  int unresolved = 0;
  for (std::size_t k = 0; k < kStatTargets; ++k) {
    if (std::isnan(s.percentiles[k])) ++unresolved;
    else CHECK(s.percentiles[k] == ref.percentiles[k]);
  }
  CHECK(unresolved > 0);
}

TEST_CASE("streamed statistics: a window cut down to a tie block counts the ties once", "[campaign][stats]") {
  // In index order: ten chunks of a column with 10 % zeros among continuous values of both signs.
  // The first windows (from 2,048 values) reach past the zeros, so zeros are kept; as N grows the
  // median's window is cut to [0, 0] and the kept zeros become copies of its one end. Then values
  // far above (drift): the final median lies just past the zeros, so it must come back unresolved
  // (NaN), which it does only if each kept zero was counted once when the window collapsed.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  const std::size_t rows = 4096, n_a = 10 * rows, n = n_a + rows + 819;
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n_a; ++i) v[i] = rng() % 10 == 0 ? 0.0 : g(rng);
  for (std::size_t i = n_a; i < n; ++i) v[i] = 1000.0 + static_cast<double>(i);
  const std::vector<std::uint8_t> use(n, 1);
  const std::size_t n_chunks = (n + rows - 1) / rows;
  ColumnStats cs;
  const char* bytes = reinterpret_cast<const char*>(v.data());
  cs.seed(bytes, rows, 1, use.data());
  REQUIRE(cs.windows()[2].lo < 0.0);  // the median's first window holds zeros strictly inside
  REQUIRE(cs.windows()[2].hi > 0.0);
  for (std::size_t c = 0; c < n_chunks; ++c) {
    const std::size_t r = std::min(rows, n - c * rows);
    cs.add(static_cast<std::int64_t>(c), calc_chunk_summary(bytes + 8 * rows * c, r, 1, use.data(), cs.windows()));
    if (c + 1 == 10) {
      REQUIRE(cs.windows()[2].lo == 0.0);  // cut down to the zeros
      REQUIRE(cs.windows()[2].hi == 0.0);
    }
  }
  bool resolved = true;
  const Stats s = cs.calc_stats(resolved);
  const Stats ref = calc_stats(v, use);
  REQUIRE(ref.percentiles[2] > 0.0);  // past the zeros
  CHECK(std::isnan(s.percentiles[2]));
  CHECK_FALSE(resolved);
  for (std::size_t k = 0; k < kStatTargets; ++k)
    if (!std::isnan(s.percentiles[k])) CHECK(s.percentiles[k] == ref.percentiles[k]);
}

TEST_CASE("streamed statistics: a chunk summary counts the values below, at the ends and inside a window",
          "[campaign][stats]") {
  std::vector<double> v = {1.0, 2.0, 2.0, 3.5, 7.0, std::numeric_limits<double>::quiet_NaN(), 100.0};
  std::vector<std::uint8_t> use(v.size(), 1);
  use[6] = 0;  // a failed run's value: not used
  Windows w;
  w[2] = {2.0, 3.5};
  const ChunkSummary s = calc_chunk_summary(reinterpret_cast<const char*>(v.data()), v.size(), 1, use.data(), w);
  CHECK(s.moments.count == 5);  // NaN and the unused row left out
  CHECK(s.moments.mean == Approx(15.5 / 5).epsilon(1e-15));
  CHECK(s.below[2] == 1);
  CHECK(s.at_lo[2] == 2);
  CHECK(s.at_hi[2] == 1);
  CHECK(s.kept[2].empty());
  CHECK(s.kept[0].size() == 5);  // an infinite window keeps every usable value
  ColumnStats cs;
  CHECK_THROWS_AS(cs.add(-1, s), std::runtime_error);
  cs.add(1, s);
  CHECK_THROWS_AS(cs.add(1, s), std::runtime_error);  // twice
  CHECK_FALSE(cs.complete(2));                        // chunk 0 missing
}

TEST_CASE("streamed statistics: a chunk summary against each kind of window, counted value by value",
          "[campaign][stats]") {
  // Windows past either end of the chunk, at its min and max, narrow (most blocks of eight hold
  // nothing inside), wide, collapsed onto a tie; row counts that are not multiples of eight.
  std::mt19937_64 rng(17);
  std::normal_distribution<double> g(0.0, 1.0);
  for (const std::size_t rows : {std::size_t{4096}, std::size_t{1003}, std::size_t{7}}) {
    std::vector<double> v(2 * rows);  // stride 2: every other value is another column's
    std::vector<std::uint8_t> use(rows);
    for (std::size_t i = 0; i < rows; ++i) {
      v[2 * i] = i % 13 == 4 ? std::numeric_limits<double>::quiet_NaN() : std::round(g(rng) * 1e3) / 1e3;
      v[2 * i + 1] = 1e300;
      use[i] = rng() % 7 != 0;
    }
    std::vector<double> x;  // the usable values, in order
    for (std::size_t i = 0; i < rows; ++i)
      if (use[i] && std::isfinite(v[2 * i])) x.push_back(v[2 * i]);
    const auto [mn, mx] = std::minmax_element(x.begin(), x.end());
    const double inf = std::numeric_limits<double>::infinity();
    const std::vector<Window> cases = {{*mx + 1.0, *mx + 2.0}, {*mn - 2.0, *mn - 1.0}, {*mn, *mx}, {-0.05, 0.05},
                                       {-inf, inf},           {0.0, 0.0},             {*mx, inf}, {inf, inf}};
    for (std::size_t c0 = 0; c0 < cases.size(); c0 += kStatTargets) {
      Windows w;
      for (std::size_t t = 0; t < kStatTargets && c0 + t < cases.size(); ++t) w[t] = cases[c0 + t];
      const ChunkSummary s = calc_chunk_summary(reinterpret_cast<const char*>(v.data()), rows, 2, use.data(), w);
      CHECK(s.moments.count == static_cast<std::int64_t>(x.size()));
      CHECK(s.moments.min == *mn);
      CHECK(s.moments.max == *mx);
      for (std::size_t t = 0; t < kStatTargets; ++t) {
        INFO("rows " << rows << ", window [" << w[t].lo << ", " << w[t].hi << "]");
        std::int64_t below = 0, at_lo = 0, at_hi = 0;
        std::vector<double> inside;
        for (const double a : x) {
          if (a < w[t].lo) ++below;
          else if (a == w[t].lo) ++at_lo;
          else if (a == w[t].hi) ++at_hi;
          else if (a < w[t].hi) inside.push_back(a);
        }
        CHECK(s.below[t] == below);
        CHECK(s.at_lo[t] == at_lo);
        CHECK(s.at_hi[t] == at_hi);
        CHECK(s.kept[t] == inside);
      }
    }
  }
}

namespace {

// The chunk summary by the definitions, value by value (column_stats.hpp): the usable values in
// row order; count, shifted mean and M2 by two plain passes; min and max by std::min/std::max in
// row order (so the first of equal values, -0.0 or +0.0, is kept); each window's counts by a
// comparison chain. A summary must match it bit for bit, since the streamed /stats must not
// depend on the kernel that made it.
ChunkSummary reference_summary(const std::vector<double>& v, std::size_t stride, const std::vector<std::uint8_t>& use,
                               const Windows& w) {
  ChunkSummary s;
  s.window = w;
  std::vector<double> x;
  for (std::size_t i = 0; i < use.size(); ++i)
    if (use[i] && std::isfinite(v[i * stride])) x.push_back(v[i * stride]);
  Moments& m = s.moments;
  m.count = static_cast<std::int64_t>(x.size());
  if (x.empty()) return s;
  double sum = 0.0;
  for (const double a : x) sum += a - x.front();
  const double dm = sum / static_cast<double>(x.size());
  m.mean = x.front() + dm;
  for (const double a : x) {
    const double d = a - x.front() - dm;
    m.m2 += d * d;
    m.min = std::min(m.min, a);
    m.max = std::max(m.max, a);
  }
  for (std::size_t t = 0; t < kStatTargets; ++t)
    for (const double a : x) {
      if (a < w[t].lo) ++s.below[t];
      else if (a == w[t].lo) ++s.at_lo[t];
      else if (a == w[t].hi) ++s.at_hi[t];
      else if (a < w[t].hi) s.kept[t].push_back(a);
    }
  return s;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("streamed statistics: chunk summaries match the definitions bit for bit",
          "[campaign][stats]") {
  // Random columns (continuous, NaN-laden, heavy ties, constant, signed zeros, signed zeros at the
  // min), random row counts (blocks of eight and four lanes, and the rows past them), strides, unused
  // rows, and random windows: between two of the chunk's values, at a value, collapsed onto one, past
  // either end.
  std::mt19937_64 rng(23);
  std::normal_distribution<double> g(0.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  ChunkSummary reused;  // made again and again into the same room, as rank 0 does
  {
    for (int trial = 0; trial < 120; ++trial) {
      const std::size_t rows = 1 + rng() % 300, stride = 1 + rng() % 3, kind = trial % 6;
      std::vector<double> v(rows * stride, 1e300);
      std::vector<std::uint8_t> use(rows);
      for (std::size_t i = 0; i < rows; ++i) {
        double a = g(rng);
        if (kind == 1 && rng() % 4 == 0) a = rng() % 2 ? nan : -inf;
        if (kind == 2) a = static_cast<double>(rng() % 4);
        if (kind == 3) a = 2.5;
        if (kind >= 4) a = rng() % 3 == 0 ? (rng() % 2 ? 0.0 : -0.0) : std::round(a);
        if (kind == 5 && a != 0.0) a = std::abs(a);  // the min a zero of either sign
        v[i * stride] = a;
        use[i] = rng() % 8 != 0;
      }
      Windows w;
      for (Window& win : w) {
        const double a = v[(rng() % rows) * stride], b = v[(rng() % rows) * stride];
        switch (rng() % 4) {
          case 0: win = {std::min(a, b), std::max(a, b)}; break;
          case 1: win = {a, a}; break;
          case 2: win = {std::min(a, b) - 0.25, std::max(a, b) + 0.25}; break;
          default: win = rng() % 2 ? Window{-inf, -1e9} : Window{1e9, inf}; break;
        }
        if (!(win.lo <= win.hi)) win = {};  // a NaN end: the infinite window
      }
      INFO("trial " << trial << ", rows " << rows << ", stride " << stride);
      const ChunkSummary s = calc_chunk_summary(reinterpret_cast<const char*>(v.data()), rows, stride, use.data(), w);
      const ChunkSummary r = reference_summary(v, stride, use, w);
      calc_chunk_summary(reinterpret_cast<const char*>(v.data()), rows, stride, use.data(), w, reused);
      CHECK(reused.moments.count == r.moments.count);
      CHECK(same_bits(reused.moments.m2, r.moments.m2));
      CHECK(s.moments.count == r.moments.count);
      CHECK(same_bits(s.moments.mean, r.moments.mean));
      CHECK(same_bits(s.moments.m2, r.moments.m2));
      CHECK(same_bits(s.moments.min, r.moments.min));
      CHECK(same_bits(s.moments.max, r.moments.max));
      for (std::size_t t = 0; t < kStatTargets; ++t) {
        INFO("window [" << w[t].lo << ", " << w[t].hi << "]");
        CHECK(s.below[t] == r.below[t]);
        CHECK(s.at_lo[t] == r.at_lo[t]);
        CHECK(s.at_hi[t] == r.at_hi[t]);
        REQUIRE(s.kept[t].size() == r.kept[t].size());
        CHECK(std::equal(s.kept[t].begin(), s.kept[t].end(), r.kept[t].begin(), same_bits));
        CHECK((reused.below[t] == r.below[t] && reused.at_lo[t] == r.at_lo[t] && reused.at_hi[t] == r.at_hi[t]));
        CHECK(reused.kept[t] == r.kept[t]);
      }
    }
  }
}

TEST_CASE("statistics: order statistics selected are the sorted values' ones",
          "[campaign][stats]") {
  // Sizes around the partitions' four lanes and the short parts that std::sort finishes; continuous
  // values, heavy ties (the pivot's copies hold a rank), one value, values sorted up and down (a
  // column that drifts); one rank, two (a window's ends), a dozen (the first windows), repeated
  // ranks, every rank of the small ones. The reference: std::sort.
  std::mt19937_64 rng(29);
  std::normal_distribution<double> g(0.0, 1.0);
  {
    for (int trial = 0; trial < 300; ++trial) {
      const std::size_t n = 1 + rng() % (trial < 100 ? 70 : 3000), kind = trial % 5;
      std::vector<double> x(n);
      for (double& a : x) a = kind == 1 ? static_cast<double>(rng() % 5) : kind == 2 ? 7.25 : g(rng);
      if (trial % 7 == 6)  // signed zeros among the values: none may lose its sign
        for (double& a : x) a = rng() % 3 == 0 ? (rng() % 2 ? 0.0 : -0.0) : a;
      const auto negative_zeros = [](const std::vector<double>& v) {
        return std::count_if(v.begin(), v.end(), [](double a) { return a == 0.0 && std::signbit(a); });
      };
      if (kind == 3) std::sort(x.begin(), x.end());
      if (kind == 4) std::sort(x.begin(), x.end(), std::greater<>());
      std::vector<double> sorted = x;
      std::sort(sorted.begin(), sorted.end());
      std::vector<std::size_t> ranks;
      if (n < 40) {
        for (std::size_t r = 0; r < n; ++r) ranks.push_back(r);
      } else {
        for (std::size_t j = 0, m = trial % 3 == 0 ? 1 : trial % 3 == 1 ? 2 : 12; j < m; ++j) ranks.push_back(rng() % n);
        std::sort(ranks.begin(), ranks.end());
      }
      std::vector<double> y = x;
      select_order_statistics(y.data(), n, ranks.data(), ranks.size());
      for (const std::size_t r : ranks) {
        INFO("trial " << trial << ", n " << n << ", rank " << r);
        CHECK(y[r] == sorted[r]);
      }
      CHECK(negative_zeros(y) == negative_zeros(x));
      std::sort(y.begin(), y.end());
      CHECK(y == sorted);  // the same values, reordered
    }
  }
}

TEST_CASE("statistics: ok runs with finite values, numpy's linear percentiles", "[campaign][stats]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Sorted 1, 2, 4, 10 (ok and finite); the 100 is a failed run, the NaN an ok run without value.
  const std::vector<double> v = {4.0, 100.0, 1.0, nan, 10.0, 2.0};
  const std::vector<std::uint8_t> ok = {1, 0, 1, 1, 1, 1};
  const Stats s = calc_stats(v, ok);
  CHECK(s.count == 4);
  CHECK(s.min == 1.0);
  CHECK(s.max == 10.0);
  CHECK(s.mean == 4.25);
  CHECK(s.std == Approx(std::sqrt((3.25 * 3.25 + 2.25 * 2.25 + 0.25 * 0.25 + 5.75 * 5.75) / 3.0)).epsilon(1e-15));
  // Index h = q/100 * 3. p50: h = 1.5 -> 2 + 0.5 * 2 = 3. p5: h = 0.15 -> 1 + 0.15. p99.865:
  // h = 2.99595, lerp from the upper end: 10 - 6 * (1 - 0.99595).
  CHECK(s.percentiles[2] == 3.0);
  CHECK(s.percentiles[1] == Approx(1.15).epsilon(1e-15));
  CHECK(s.percentiles[5] == Approx(10.0 - 6.0 * (1.0 - 0.99595)).epsilon(1e-15));
  const std::vector<double> sorted = {1, 2, 4, 10};
  CHECK(calc_percentile_sorted(sorted, 0.0) == 1.0);
  CHECK(calc_percentile_sorted(sorted, 100.0) == 10.0);
  const Stats none = calc_stats({nan, 3.0}, {1, 0});
  CHECK(none.count == 0);
  CHECK(std::isnan(none.mean));
  CHECK(std::isnan(none.percentiles[0]));
  CHECK(std::isnan(calc_stats({3.0}, {1}).std));  // one value: no sample deviation
}

TEST_CASE("statistics of large columns: the order statistics of a full sort", "[campaign][stats]") {
  // Large columns with narrow spread, heavy ties, an outlier and both signs: compare with std::sort
  // and the same interpolation formula (exact equality: the same two order statistics, the same
  // arithmetic).
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(1.25, 0.01);
  const std::size_t n = 50000;
  std::vector<std::vector<double>> columns(4, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    columns[0][i] = g(rng);                                        // a load: narrow spread
    columns[1][i] = static_cast<double>(rng() % 3) - 1.0;          // heavy ties: -1, 0, 1
    columns[2][i] = i == 17 ? 1e300 : -g(rng) * 1e-6;              // one far outlier: nearly all in one bucket
    columns[3][i] = (rng() % 2 ? 1.0 : -1.0) * std::exp(10 * g(rng));  // both signs, wide range
  }
  const std::vector<std::uint8_t> use(n, 1);
  for (const auto& c : columns) {
    const Stats st = calc_stats(c, use);
    std::vector<double> sorted = c;
    std::sort(sorted.begin(), sorted.end());
    CHECK(st.min == sorted.front());
    CHECK(st.max == sorted.back());
    for (std::size_t k = 0; k < kStatPercentiles.size(); ++k) CHECK(st.percentiles[k] == calc_percentile_sorted(sorted, kStatPercentiles[k]));
  }
}
