// Streamed column statistics: the equations and the window rule are in column_stats.hpp.
#include "statistics/column_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::statistics {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kSigmas = 6.0;        // half-width of a window in binomial standard deviations of rank
// The first windows hold about 25 % of a chunk's values summed over the six targets (from a chunk
// of 4,096 values); most of the merging and narrowing happens while they are that wide, so margin
// and slack are small (a miss costs a read-back at the end, never a wrong number).
constexpr std::int64_t kMargin = 16;   // ... plus this many ranks (small N, ties)
constexpr std::size_t kSlack = 256;    // narrow only past 3 w + kSlack kept values: amortised O(1) a value

double target_p(std::size_t t) { return kStatPercentiles[t] / 100.0; }

std::int64_t half_width(std::int64_t n, double p) {
  return static_cast<std::int64_t>(std::ceil(kSigmas * std::sqrt(static_cast<double>(n) * p * (1.0 - p)))) + kMargin;
}

// The values of a window, in order: at_lo copies of lo, kept (unordered), at_hi copies of hi.
struct WindowValues {
  Window w;
  std::int64_t at_lo, at_hi;
  std::vector<double>& kept;
  std::int64_t size() const { return at_lo + static_cast<std::int64_t>(kept.size()) + at_hi; }
  // Puts the order statistics i[0..n) (ascending) in their places (select_order_statistics):
  // reorders kept.
  void select(const std::int64_t* i, std::size_t n) {
    std::array<std::size_t, 2 * kStatTargets> k{};
    std::size_t m = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (i[j] >= at_lo && i[j] - at_lo < static_cast<std::int64_t>(kept.size()))
        k[m++] = static_cast<std::size_t>(i[j] - at_lo);
    select_order_statistics(kept.data(), kept.size(), k.data(), m);
  }
  double at(std::int64_t i) const {  // the i-th smallest, once selected
    if (i < at_lo) return w.lo;
    const auto k = static_cast<std::size_t>(i - at_lo);
    return k < kept.size() ? kept[k] : w.hi;
  }
};

// The window around the estimate of target p (`below` values under v's window, n in all): cut to
// w ranks past the estimate on each side that holds more. The current window when the estimate is
// not among v's values.
struct WindowRanks {
  bool cut = false;  // the estimate lies among the window's values
  std::int64_t lo = 0, hi = 0;  // the ranks among them of the new ends, when cut: lo > 0, hi < size - 1
};

WindowRanks find_window_ranks(std::int64_t size, std::int64_t below, std::int64_t n, double p) {
  const double r = p * static_cast<double>(n - 1) - static_cast<double>(below);
  if (size == 0 || r < 0.0 || r > static_cast<double>(size - 1)) return {};
  const std::int64_t w = half_width(n, p);
  return {true, static_cast<std::int64_t>(std::floor(r)) - w, static_cast<std::int64_t>(std::ceil(r)) + w};
}

// `selected`: v's order statistics are in their places already.
Window calc_window(WindowValues v, std::int64_t below, std::int64_t n, double p, bool selected = false) {
  const std::int64_t size = v.size();
  const WindowRanks k = find_window_ranks(size, below, n, p);
  Window cur = v.w;
  if (!k.cut) return cur;
  const std::int64_t ends[2] = {k.lo, k.hi};
  if (!selected) v.select(ends, 2);
  if (k.hi < size - 1) cur.hi = std::min(cur.hi, v.at(k.hi));
  if (k.lo > 0) cur.lo = std::max(cur.lo, v.at(k.lo));
  return cur;
}


// The values of x[0..n) (finite) against the window (lo, hi): those below lo and at each end
// counted, those strictly inside stored to out[0..inside) in their order (out may be x: a store never
// passes the value read).
struct WindowCount {
  std::int64_t below = 0, at_lo = 0, at_hi = 0;
  std::size_t inside = 0;
};

// Values x[from..to) one by one into c and out[k...], without a branch on the values.
void count_values(const double* x, std::size_t from, std::size_t to, double lo, double hi, WindowCount& c,
                  double* out, std::size_t& k) {
  for (std::size_t i = from; i < to; ++i) {
    const double v = x[i];
    c.below += v < lo;
    c.at_lo += v == lo;
    c.at_hi += v == hi;
    out[k] = v;
    k += (v > lo) & (v < hi);
  }
}

// In two passes over blocks of kBlock values: the first counts the values below lo and lists the
// blocks that hold a value in [lo, hi] (a minority once a window has narrowed), the second counts
// and stores those blocks' values one by one. Neither branches on the values.
constexpr std::size_t kBlock = 8;

WindowCount count_window(const double* x, std::size_t n, double lo, double hi, double* out,
                         std::vector<std::uint32_t>& blocks) {
  const std::size_t n_blocks = n / kBlock;
  if (blocks.size() < n_blocks) blocks.resize(n_blocks);
  std::size_t listed = 0;
  WindowCount c;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const double* xb = x + kBlock * b;
    std::int64_t below = 0, in = 0;
    for (std::size_t j = 0; j < kBlock; ++j) {
      below += xb[j] < lo;
      in += (xb[j] >= lo) & (xb[j] <= hi);
    }
    c.below += below;
    blocks[listed] = static_cast<std::uint32_t>(b);
    listed += in != 0;
  }
  std::size_t k = 0;
  for (std::size_t j = 0; j < listed; ++j) {
    WindowCount cb;  // the block's values below lo are counted already
    count_values(x + kBlock * blocks[j], 0, kBlock, lo, hi, cb, out, k);
    c.at_lo += cb.at_lo;
    c.at_hi += cb.at_hi;
  }
  count_values(x, kBlock * n_blocks, n, lo, hi, c, out, k);
  c.inside = k;
  return c;
}

}  // namespace

Moments combine(const Moments& a, const Moments& b) {
  if (a.count == 0) return b;
  if (b.count == 0) return a;
  Moments m;
  m.count = a.count + b.count;
  const auto na = static_cast<double>(a.count), nb = static_cast<double>(b.count), n = static_cast<double>(m.count);
  const double d = b.mean - a.mean;
  m.mean = a.mean + d * (nb / n);
  m.m2 = a.m2 + b.m2 + d * d * (na * nb / n);
  m.min = std::min(a.min, b.min);
  m.max = std::max(a.max, b.max);
  return m;
}

ChunkSummary calc_chunk_summary(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                                const Windows& w) {
  ChunkSummary s;
  calc_chunk_summary(values, rows, stride, use, w, s);
  return s;
}

void calc_chunk_summary(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                        const Windows& w, ChunkSummary& s) {
  s.window = w;
  s.moments = {};
  s.below = s.at_lo = s.at_hi = {};
  for (std::vector<double>& k : s.kept) k.clear();  // their room is used again
  // The usable values in row order (branch-free: failed runs and NaN are not predictable).
  std::vector<double>& x = s.work_values;
  if (x.size() < rows) x.resize(rows);
  std::size_t n = 0;
  for (std::size_t i = 0; i < rows; ++i) {
    double v;
    std::memcpy(&v, values + 8 * i * stride, 8);
    x[n] = v;
    n += (use[i] != 0) & std::isfinite(v);
  }
  if (n == 0) return;
  Moments& m = s.moments;
  m.count = static_cast<std::int64_t>(n);
  const double x0 = x[0];
  double sum = 0.0, lo = m.min, hi = m.max;
  for (std::size_t i = 0; i < n; ++i) {
    sum += x[i] - x0;
    lo = std::min(lo, x[i]);
    hi = std::max(hi, x[i]);
  }
  m.min = lo;
  m.max = hi;
  const double dm = sum / static_cast<double>(n);  // the mean's shift from x0
  m.mean = x0 + dm;
  double m2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) m2 += (x[i] - x0 - dm) * (x[i] - x0 - dm);
  m.m2 = m2;
  if (s.work_inside.size() < n) s.work_inside.resize(n);
  // Per target: a window past the chunk's values is settled by its min and max, the others counted.
  for (std::size_t t = 0; t < kStatTargets; ++t) {
    if (m.max < w[t].lo) {
      s.below[t] = m.count;
    } else if (m.min <= w[t].hi) {
      const WindowCount c = count_window(x.data(), n, w[t].lo, w[t].hi, s.work_inside.data(), s.work_blocks);
      s.kept[t].assign(s.work_inside.data(), s.work_inside.data() + c.inside);
      s.below[t] = c.below;
      s.at_lo[t] = c.at_lo;
      s.at_hi[t] = w[t].lo == w[t].hi ? 0 : c.at_hi;  // one end: its copies are at_lo
    }
  }
}

Windows calc_first_windows(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use) {
  std::vector<double> x;
  x.reserve(rows);
  unsigned zeros = 0;  // bit 0: +0.0 seen, bit 1: -0.0 seen
  for (std::size_t i = 0; i < rows; ++i) {
    double v;
    std::memcpy(&v, values + 8 * i * stride, 8);
    if (!use[i] || !std::isfinite(v)) continue;
    x.push_back(v);
    if (v == 0.0) zeros |= std::signbit(v) ? 2u : 1u;
  }
  const bool mixed_zeros = zeros == 3;
  // Each window end's order statistic put in its place (a look-up then, as in sorted values).
  // Sorted instead where +0.0 and -0.0 both occur: which of them lands at a rank depends on the
  // algorithm, and the windows must not.
  const auto n = static_cast<std::int64_t>(x.size());
  Windows w{};
  if (mixed_zeros) {
    std::sort(x.begin(), x.end());
  } else {
    std::vector<std::int64_t> ranks;
    for (std::size_t t = 0; t < kStatTargets; ++t) {
      const WindowRanks k = find_window_ranks(n, 0, n, target_p(t));
      if (k.cut) ranks.insert(ranks.end(), {k.lo, k.hi});
    }
    std::sort(ranks.begin(), ranks.end());
    ranks.erase(std::unique(ranks.begin(), ranks.end()), ranks.end());
    WindowValues{w[0], 0, 0, x}.select(ranks.data(), ranks.size());
  }
  for (std::size_t t = 0; t < kStatTargets; ++t) w[t] = calc_window({w[t], 0, 0, x}, 0, n, target_p(t), true);
  return w;
}

void ColumnStats::seed(const Windows& w) {
  if (seeded_ || count_ > 0) return;
  seeded_ = true;
  win_ = w;
}

// k copies of v (of a summary made against a wider window, or of a window being cut) into target
// t's window; values above it are dropped.
void ColumnStats::put(std::size_t t, double v, std::int64_t k) {
  const Window& w = win_[t];
  if (v < w.lo) below_[t] += k;
  else if (v == w.lo) at_lo_[t] += k;
  else if (v < w.hi) kept_[t].insert(kept_[t].end(), static_cast<std::size_t>(k), v);
  else if (v == w.hi) at_hi_[t] += k;
}

// put(t, v, 1) for each of kept_[t][from..]: the values inside stay, in their order, the others are
// counted or dropped (count_window: a value's side of the window ends is not predictable).
void ColumnStats::classify_kept(std::size_t t, std::size_t from) {
  std::vector<double>& x = kept_[t];
  const double lo = win_[t].lo, hi = win_[t].hi;
  const WindowCount c = count_window(x.data() + from, x.size() - from, lo, hi, x.data() + from, blocks_);
  x.resize(from + c.inside);
  below_[t] += c.below;
  at_lo_[t] += c.at_lo;
  at_hi_[t] += lo == hi ? 0 : c.at_hi;  // one end: its copies are at_lo (as put)
}

void ColumnStats::add(std::int64_t chunk, const ChunkSummary& s) {
  if (chunk < 0) throw std::runtime_error(fmt::format("column statistics: chunk {} out of range", chunk));
  const auto c = static_cast<std::size_t>(chunk);
  if (c >= chunks_.size()) {
    chunks_.resize(c + 1);
    have_.resize(c + 1, 0);
  }
  if (have_[c]) throw std::runtime_error(fmt::format("column statistics: chunk {} merged twice", chunk));
  have_[c] = 1;
  chunks_[c] = s.moments;
  count_ += s.moments.count;
  seeded_ = true;
  for (std::size_t t = 0; t < kStatTargets; ++t) {
    // The summary's window contains this one (windows only narrow): its ends and its kept values
    // are re-classified here; its values above hi are gone, as they would be here.
    below_[t] += s.below[t];
    if (s.at_lo[t] > 0) put(t, s.window[t].lo, s.at_lo[t]);
    if (s.at_hi[t] > 0) put(t, s.window[t].hi, s.at_hi[t]);
    const std::size_t from = kept_[t].size();
    kept_[t].insert(kept_[t].end(), s.kept[t].begin(), s.kept[t].end());
    // Made against this very window (the usual case): every kept value is inside it.
    if (s.window[t].lo != win_[t].lo || s.window[t].hi != win_[t].hi) classify_kept(t, from);
    narrow(t);
  }
}

void ColumnStats::narrow(std::size_t t) {
  std::vector<double>& x = kept_[t];
  const double p = target_p(t);
  const auto limit = static_cast<std::size_t>(3 * half_width(count_, p)) + kSlack;
  if (x.size() <= std::max(limit, next_cut_[t])) return;
  next_cut_[t] = 2 * x.size();
  const Window old = win_[t];
  const std::int64_t old_lo = at_lo_[t], old_hi = at_hi_[t];
  const double r = p * static_cast<double>(count_ - 1) - static_cast<double>(below_[t]);
  if (r < 0.0 || r > static_cast<double>(old_lo + static_cast<std::int64_t>(x.size()) + old_hi - 1)) {
    // The estimate has left the window (values drift with the run index): give the target up
    // rather than keep a growing window; the end reads the column back. Every value now counts
    // as below an empty window at +infinity.
    win_[t] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    below_[t] += old_lo + static_cast<std::int64_t>(x.size()) + old_hi;
    at_lo_[t] = at_hi_[t] = 0;
    std::vector<double>().swap(x);
    return;
  }
  const Window w = calc_window({old, old_lo, old_hi, x}, below_[t], count_, p);
  if (w.lo == old.lo && w.hi == old.hi) return;
  win_[t] = w;
  at_lo_[t] = at_hi_[t] = 0;
  put(t, old.lo, old_lo);  // the old ends' copies: below the new lo, at an end, or gone (never inside)
  put(t, old.hi, old_hi);
  classify_kept(t, 0);
  next_cut_[t] = std::max(next_cut_[t] / 2, 2 * x.size());
}

Stats ColumnStats::calc_stats(bool& resolved) const {
  resolved = true;
  Moments m;
  for (std::size_t c = 0; c < chunks_.size(); ++c)
    if (have_[c]) m = combine(m, chunks_[c]);
  Stats s;
  s.count = m.count;
  if (m.count == 0) {
    s.mean = s.std = s.min = s.max = kNaN;
    s.percentiles.fill(kNaN);
    return s;
  }
  s.mean = m.mean;
  s.std = m.count > 1 ? std::sqrt(m.m2 / static_cast<double>(m.count - 1)) : kNaN;
  s.min = m.min;
  s.max = m.max;
  std::vector<double> x;
  for (std::size_t t = 0; t < kStatTargets; ++t) {
    const PercentileIndex idx = find_percentile_index(static_cast<std::size_t>(m.count), kStatPercentiles[t]);
    const auto lo = static_cast<std::int64_t>(idx.lo) - below_[t], hi = static_cast<std::int64_t>(idx.hi) - below_[t];
    x = kept_[t];
    WindowValues v{win_[t], at_lo_[t], at_hi_[t], x};
    const std::int64_t ends[2] = {lo, hi};
    v.select(ends, 2);
    if (lo < 0 || hi >= v.size()) {
      resolved = false;
      s.percentiles[t] = kNaN;
      continue;
    }
    const double a = v.at(lo);
    s.percentiles[t] = lerp_numpy(a, hi == lo ? a : v.at(hi), idx.t);
  }
  return s;
}

bool ColumnStats::complete(std::int64_t n_chunks) const {
  return static_cast<std::int64_t>(have_.size()) == n_chunks &&
         std::all_of(have_.begin(), have_.end(), [](std::uint8_t h) { return h != 0; });
}

std::size_t ColumnStats::kept_values() const {
  std::size_t k = 0;
  for (const auto& x : kept_) k += x.size();
  return k;
}

}  // namespace truss::statistics
