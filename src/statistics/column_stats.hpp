// Streamed statistics of one output column (the Stats of stats.hpp), built from the run-index
// chunks of the results file as they are written, so that the end of a campaign does not read the
// file back (the tail must not grow with the number of runs).
//
//   count, mean, std, min, max: each chunk's usable values (ok runs, finite) give (n, mean, M2)
//     by two passes shifted by the chunk's first value; the chunks are combined in chunk-index
//     order with the pairwise update of Chan, Golub & LeVeque (1979):
//         n = na + nb,  d = mean_b - mean_a,  mean = mean_a + d nb / n,  M2 = M2a + M2b + d^2 na nb / n,
//     std = sqrt(M2 / (n - 1)). The order of completion (ranks, --resume) does not change a bit.
//   percentiles: exact order statistics with numpy's linear interpolation (calc_stats). For each
//     percentile p a window [lo, hi] of values is kept with the count of values below it. The
//     windows start from the first chunk that completes and only ever narrow: once a window holds
//     more than 3 w + 256 values it is cut to w = 6 sqrt(N p (1 - p)) + 16 ranks on each side of the
//     running estimate p (N - 1) (N: values so far), six binomial standard deviations of where the
//     final order statistic can still move for exchangeable runs. Kept values grow as sqrt(N): at
//     most about 25,000 per column at 10^6 runs (0.2 MB).
//     Values equal to a window's ends are counted, not kept (a constant or discrete column then
//     costs nothing), and a window whose cut does not shrink it is tried again only at twice its size.
//     At the end the order statistics are selected among the kept values; if one lies outside its
//     window (a column whose distribution drifts with the run index, e.g. a sorted sweep), the
//     column is reported unresolved (a target whose estimate leaves its window while it is cut is
//     given up at once, so memory stays bounded) and the caller computes its percentiles from the
//     stored column: exact either way, only slower.
//
// A summary made against older, wider windows (windows only narrow) is re-classified exactly when
// it is merged.
//
// Each chunk's usable values are gathered in row order, their shifted sum and M2 added in that
// order, min and max taken as std::min/std::max take them in that order (the first of equal values:
// -0.0 or +0.0), so a summary is a pure function of the chunk's bytes and the windows.
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "statistics/stats.hpp"

namespace truss::statistics {

inline constexpr std::size_t kStatTargets = kStatPercentiles.size();

struct Moments {
  std::int64_t count = 0;  // usable values
  double mean = 0.0, m2 = 0.0;
  double min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity();
};
Moments combine(const Moments& a, const Moments& b);  // Chan, Golub & LeVeque

struct Window {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
};
using Windows = std::array<Window, kStatTargets>;  // one per percentile of kStatPercentiles

// One column of one chunk against given windows.
struct ChunkSummary {
  Windows window;  // the windows it was made against
  Moments moments;
  std::array<std::int64_t, kStatTargets> below{};   // usable values < lo
  std::array<std::int64_t, kStatTargets> at_lo{};   // == lo
  std::array<std::int64_t, kStatTargets> at_hi{};   // == hi (when hi > lo)
  std::array<std::vector<double>, kStatTargets> kept;  // lo < value < hi
  // Work space of calc_chunk_summary, kept so that a summary made again into the same room
  // allocates nothing: the usable values, the values inside a window, the blocks listed.
  std::vector<double> work_values, work_inside;
  std::vector<std::uint32_t> work_blocks;
};

// values[i * stride] (native float64 bytes, any alignment) for i < rows, used where use[i] != 0
// and the value is finite.
ChunkSummary calc_chunk_summary(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                                const Windows& w);
// The same into s, whose vectors' room is used again (rank 0 makes one summary per column and chunk).
void calc_chunk_summary(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                        const Windows& w, ChunkSummary& s);
// The first windows of a column, from a complete chunk's usable values (all of them: a window's
// half-width is in ranks of these values, so that the more there are, the narrower the windows the
// first chunks are summarised against, and the fewer values they keep).
Windows calc_first_windows(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use);

class ColumnStats {
 public:
  const Windows& windows() const { return win_; }
  bool seeded() const { return seeded_; }
  // The first windows (before any summary is merged; ignored after): calc_first_windows.
  void seed(const Windows& w);
  void seed(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use) {
    seed(calc_first_windows(values, rows, stride, use));
  }
  // Merges chunk `chunk`'s summary (made against these windows or older ones). Throws
  // std::runtime_error for a negative chunk index or a chunk merged twice.
  void add(std::int64_t chunk, const ChunkSummary& s);
  // The statistics so far; `resolved` is false when a percentile's order statistics are not
  // among the kept values (that percentile is then NaN).
  Stats calc_stats(bool& resolved) const;
  std::size_t kept_values() const;  // memory held, for benchmarks and tests
  bool complete(std::int64_t n_chunks) const;  // chunks 0 .. n_chunks - 1 merged, and no other

 private:
  void narrow(std::size_t t);
  void put(std::size_t t, double v, std::int64_t k);
  void classify_kept(std::size_t t, std::size_t from);
  std::vector<Moments> chunks_;
  std::vector<std::uint8_t> have_;
  std::int64_t count_ = 0;
  bool seeded_ = false;
  Windows win_{};
  std::array<std::int64_t, kStatTargets> below_{}, at_lo_{}, at_hi_{};
  std::array<std::vector<double>, kStatTargets> kept_;
  std::array<std::size_t, kStatTargets> next_cut_{};  // kept size at which to try narrowing again
  std::vector<std::uint32_t> blocks_;                  // work space of classify_kept
};

}  // namespace truss::statistics
