// The inner loops of the streamed column statistics (column_stats.hpp), apart because they hold
// the vector kernels: a chunk's usable values gathered with their shifted sum, min and max, and
// counted against a percentile window; the order statistics that cut a window, selected. Every
// result is the same, bit for bit, with either kernel (use_avx2_kernels) as with the plain
// definitions.
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "sampling/stats.hpp"

namespace truss::sampling {

inline constexpr std::size_t kBlock = 8;  // values a block: one test whether any lies in [lo, hi]

struct WindowCount {
  std::int64_t below = 0, at_lo = 0, at_hi = 0;
  std::size_t inside = 0;  // values strictly inside: the first ones of CountScratch::out
};

// Room for count_window's work on n values.
struct CountScratch {
  std::vector<double> out;
  std::vector<std::uint32_t> blocks;
  void resize(std::size_t n) {
    if (out.size() < n) out.resize(n);
    if (blocks.size() < n / kBlock) blocks.resize(n / kBlock);
  }
};

// x[0..n) (finite values) against the window (lo, hi): the values below and at each end counted,
// those strictly inside stored to scratch.out in their order.
WindowCount count_window(const double* x, std::size_t n, double lo, double hi, CountScratch& scratch);

// The M2 of x about x0 + dm (its terms added in index order) and, as count_window, x against each
// window (lo[t], hi[t]) for t < nw (at most kStatTargets): counts into c[t], the values inside
// into *kept[t].
double count_windows_m2(const std::vector<double>& x, double x0, double dm, std::size_t nw, const double* lo,
                        const double* hi, WindowCount* c, std::vector<double>* const* kept, CountScratch& scratch);

// Puts the order statistics of the finite values x[0..n) at ranks r[0..k) (0-based, ascending, < n)
// in their places, as a sort would (of -0.0 and +0.0 at a rank, either one); x is only reordered.
void select_order_statistics(double* x, std::size_t n, const std::size_t* r, std::size_t k);

struct Gathered {
  std::size_t count = 0;
  double sum = 0.0;  // of value - x0 (x0: the first usable value)
  double min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity();
};

// The usable values (use[i] != 0, finite) of values[i * stride] for rows i >= first (row `first`
// usable, its value x0) gathered into x in order, with their sum of (value - x0) in index order and
// their min and max as std::min/std::max give them in index order.
Gathered gather_usable(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                       std::size_t first, double* x);

}  // namespace truss::sampling
