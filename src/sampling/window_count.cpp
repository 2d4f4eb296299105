// The inner loops of the streamed column statistics: the usable values of a chunk's column
// gathered and summed, counted against a percentile window, and order statistics selected
// (window_count.hpp).
#include "sampling/window_count.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "sampling/column_stats.hpp"

namespace truss::sampling {

namespace {

// Two doubles and their lane masks (-1 where true): GCC's and clang's vector extensions, one SSE2
// register on baseline x86-64 (NEON elsewhere).
using Vec2 = double __attribute__((vector_size(16)));
using Mask2 = decltype(Vec2{} < Vec2{});

// The values of one block of x against the window: those at either end counted, those strictly
// inside appended to out[k...] in their order. Branch-free: which are inside is not predictable.
inline void classify_block(const double* x, double lo, double hi, WindowCount& c, double* out, std::size_t& k) {
  for (std::size_t j = 0; j < kBlock; ++j) {
    const double v = x[j];
    c.at_lo += v == lo;
    c.at_hi += v == hi;
    out[k] = v;
    k += (v > lo) & (v < hi);
  }
}

// count_window's whole blocks, in two passes. The first compares each vector twice (below lo, not
// above hi), counts the values below, and lists the blocks with a value in [lo, hi] (a minority once
// the windows narrow) without a branch; the second classifies the listed blocks. A branch per block
// instead was mispredicted at about every listed block. `blocks`: room for n_blocks indices.
WindowCount count_blocks_generic(const double* x, std::size_t n_blocks, double lo, double hi, std::uint32_t* blocks,
                                 double* out, std::size_t& k) {
  const Vec2 lo2 = {lo, lo}, hi2 = {hi, hi};
  Mask2 below{};
  std::size_t listed = 0;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const double* xb = x + kBlock * b;
    Mask2 in{};
    for (std::size_t j = 0; j < kBlock; j += 2) {
      Vec2 v;
      std::memcpy(&v, xb + j, sizeof v);
      const Mask2 lt = v < lo2;
      below -= lt;
      in |= (v >= lo2) & (v <= hi2);  // x is finite: not below lo
    }
    blocks[listed] = static_cast<std::uint32_t>(b);
    listed += (in[0] | in[1]) != 0;
  }
  WindowCount c;
  c.below = below[0] + below[1];
  for (std::size_t j = 0; j < listed; ++j) classify_block(x + kBlock * blocks[j], lo, hi, c, out, k);
  return c;
}

#if defined(__x86_64__)
// Left-packing four doubles by a 4-bit mask of lanes: for each mask the 32-bit lanes of its set
// doubles, in order (AVX2 has no compress instruction).
struct PackTable {
  alignas(32) std::int32_t lanes[16][8]{};
  std::uint8_t count[16]{};
  constexpr PackTable() {
    for (int m = 0; m < 16; ++m)
      for (int j = 0; j < 4; ++j)
        if (m >> j & 1) {
          lanes[m][2 * count[m]] = 2 * j;
          lanes[m][2 * count[m] + 1] = 2 * j + 1;
          ++count[m];
        }
  }
};
constexpr PackTable kPack;

// count_blocks_avx2's second pass: the listed blocks classified four values at a time, the ends
// counted, the values inside left-packed into out (up to 4 slots past k written: k stays below the
// index of the vector, so they lie within x's length).
__attribute__((target("avx2"))) WindowCount classify_listed_avx2(const double* x, const std::uint32_t* blocks,
                                                                  std::size_t listed, double lo, double hi,
                                                                  double* out, std::size_t& k) {
  const __m256d lo4 = _mm256_set1_pd(lo), hi4 = _mm256_set1_pd(hi);
  __m256i at_lo = _mm256_setzero_si256(), at_hi = at_lo;
  for (std::size_t j = 0; j < 2 * listed; ++j) {  // the listed blocks' vectors
    const __m256d v = _mm256_loadu_pd(x + kBlock * blocks[j / 2] + 4 * (j % 2));
    at_lo = _mm256_sub_epi64(at_lo, _mm256_castpd_si256(_mm256_cmp_pd(v, lo4, _CMP_EQ_OQ)));
    at_hi = _mm256_sub_epi64(at_hi, _mm256_castpd_si256(_mm256_cmp_pd(v, hi4, _CMP_EQ_OQ)));
    const __m256d inside = _mm256_and_pd(_mm256_cmp_pd(v, lo4, _CMP_GT_OQ), _mm256_cmp_pd(v, hi4, _CMP_LT_OQ));
    const int m = _mm256_movemask_pd(inside);
    const __m256i perm = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.lanes[m]));
    _mm256_storeu_pd(out + k, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(v), perm)));
    k += kPack.count[m];
  }
  alignas(32) std::int64_t lanes[2][4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes[0]), at_lo);
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes[1]), at_hi);
  WindowCount c;
  for (std::size_t j = 0; j < 4; ++j) {
    c.at_lo += lanes[0][j];
    c.at_hi += lanes[1][j];
  }
  return c;
}

// The first pass of count_blocks_generic for nw windows at once, four lanes at a time (AVX2: chosen
// at run time, the binary stays baseline x86-64), with `m2`'s additions riding along when asked
// (they are bound by their latency, which leaves room for the comparisons). Window t's listed
// blocks go to blocks[t * n_blocks ...].
template <bool kM2>
__attribute__((target("avx2"))) void list_blocks_avx2(const double* x, std::size_t n_blocks, double x0, double dm,
                                                      double& m2, std::size_t nw, const double* lo, const double* hi,
                                                      std::int64_t* below, std::uint32_t* blocks, std::size_t* listed) {
  __m256d lo4[kStatTargets], hi4[kStatTargets];
  __m256i bel[kStatTargets];
  std::size_t n_listed[kStatTargets];
  for (std::size_t t = 0; t < nw; ++t) {
    lo4[t] = _mm256_set1_pd(lo[t]);
    hi4[t] = _mm256_set1_pd(hi[t]);
    bel[t] = _mm256_setzero_si256();
    n_listed[t] = 0;
  }
  double acc = m2;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const double* xb = x + kBlock * b;
    if constexpr (kM2)
      for (std::size_t j = 0; j < kBlock; ++j) acc += (xb[j] - x0 - dm) * (xb[j] - x0 - dm);
    const __m256d v0 = _mm256_loadu_pd(xb), v1 = _mm256_loadu_pd(xb + 4);
    for (std::size_t t = 0; t < nw; ++t) {
      const __m256d lt0 = _mm256_cmp_pd(v0, lo4[t], _CMP_LT_OQ), lt1 = _mm256_cmp_pd(v1, lo4[t], _CMP_LT_OQ);
      bel[t] = _mm256_sub_epi64(bel[t], _mm256_castpd_si256(lt0));
      bel[t] = _mm256_sub_epi64(bel[t], _mm256_castpd_si256(lt1));
      const __m256d in0 = _mm256_andnot_pd(lt0, _mm256_cmp_pd(v0, hi4[t], _CMP_LE_OQ));
      const __m256d in1 = _mm256_andnot_pd(lt1, _mm256_cmp_pd(v1, hi4[t], _CMP_LE_OQ));
      blocks[t * n_blocks + n_listed[t]] = static_cast<std::uint32_t>(b);
      n_listed[t] += _mm256_movemask_pd(_mm256_or_pd(in0, in1)) != 0;
    }
  }
  m2 = acc;
  for (std::size_t t = 0; t < nw; ++t) {
    alignas(32) std::int64_t lanes[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), bel[t]);
    below[t] = lanes[0] + lanes[1] + lanes[2] + lanes[3];
    listed[t] = n_listed[t];
  }
}

WindowCount count_blocks_avx2(const double* x, std::size_t n_blocks, double lo, double hi, std::uint32_t* blocks,
                              double* out, std::size_t& k) {
  double m2 = 0.0;
  std::int64_t below = 0;
  std::size_t listed = 0;
  list_blocks_avx2<false>(x, n_blocks, 0.0, 0.0, m2, 1, &lo, &hi, &below, blocks, &listed);
  WindowCount c = classify_listed_avx2(x, blocks, listed, lo, hi, out, k);
  c.below = below;
  return c;
}
#endif

bool has_avx2() {
#if defined(__x86_64__)
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

bool& avx2_enabled() {  // the kernels' switch: use_avx2_kernels
  static bool on = has_avx2();
  return on;
}

WindowCount count_blocks(const double* x, std::size_t n_blocks, double lo, double hi, std::uint32_t* blocks,
                         double* out, std::size_t& k) {
#if defined(__x86_64__)
  if (avx2_enabled()) return count_blocks_avx2(x, n_blocks, lo, hi, blocks, out, k);
#endif
  return count_blocks_generic(x, n_blocks, lo, hi, blocks, out, k);
}

}  // namespace

namespace {

// Values x[from..n) (past the whole blocks) against the window, one by one.
void count_rest(const double* x, std::size_t from, std::size_t n, double lo, double hi, WindowCount& c, double* out,
                std::size_t& k) {
  for (std::size_t i = from; i < n; ++i) {
    const double v = x[i];
    c.below += v < lo;
    c.at_lo += v == lo;
    c.at_hi += v == hi;
    out[k] = v;
    k += (v > lo) & (v < hi);
  }
}

}  // namespace

WindowCount count_window(const double* x, std::size_t n, double lo, double hi, CountScratch& scratch) {
  scratch.resize(n);
  const std::size_t n_blocks = n / kBlock;
  std::size_t k = 0;
  WindowCount c = count_blocks(x, n_blocks, lo, hi, scratch.blocks.data(), scratch.out.data(), k);
  count_rest(x, kBlock * n_blocks, n, lo, hi, c, scratch.out.data(), k);
  c.inside = k;
  return c;
}

namespace {

// gather_usable's loop over rows [i, rows), continuing g (x0: the first usable value, n: values
// gathered so far). A row not used adds +0.0, which leaves the sum's bits alone (the sum is never
// -0.0); bound by the latency of the additions as the M2 pass is.
void gather_rows(const char* values, std::size_t i, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                 double x0, double* x, Gathered& g) {
  double sum = g.sum, lo = g.min, hi = g.max;
  std::size_t n = g.count;
  for (; i < rows; ++i) {  // branch-free: failed runs and NaN are not predictable
    double v;
    std::memcpy(&v, values + 8 * i * stride, 8);
    const bool ok = (use[i] != 0) & std::isfinite(v);
    x[n] = v;
    n += ok;
    sum += ok ? v - x0 : 0.0;
    lo = ok && v < lo ? v : lo;  // std::min's choice among equal values (-0.0 and +0.0): the first
    hi = ok && hi < v ? v : hi;
  }
  g.count = n;
  g.sum = sum;
  g.min = lo;
  g.max = hi;
}

// The value among x[0..n) equal to m that comes first (-0.0 or +0.0 where m is a zero).
double find_first_equal(const double* x, std::size_t n, double m) {
  if (m != 0.0) return m;
  for (std::size_t i = 0; i < n; ++i)
    if (x[i] == 0.0) return x[i];
  return m;
}

#if defined(__x86_64__)
// gather_rows four rows at a time (AVX2): the usable ones left-packed into x, their shifted values
// added one by one in row order (the same additions), min and max per lane (each lane keeps its
// first of equal values; across lanes only a zero's sign can differ, so the first zero of x is then
// looked up). Rows of a per-bay block (stride > 1) are loaded one by one. Returns the first row not
// done.
__attribute__((target("avx2"))) std::size_t gather_rows_avx2(const char* values, std::size_t first, std::size_t rows,
                                                              std::size_t stride, const std::uint8_t* use, double x0,
                                                              double* x, Gathered& g) {
  const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffff));
  const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity()), x04 = _mm256_set1_pd(x0);
  __m256d lo = inf, hi = _mm256_sub_pd(_mm256_setzero_pd(), inf);
  double sum = g.sum;
  std::size_t n = g.count, i = first;
  for (; i + 4 <= rows; i += 4) {
    __m256d d;
    if (stride == 1) {
      d = _mm256_loadu_pd(reinterpret_cast<const double*>(values + 8 * i));
    } else {
      double r[4];
      for (std::size_t j = 0; j < 4; ++j) std::memcpy(&r[j], values + 8 * (i + j) * stride, 8);
      d = _mm256_set_pd(r[3], r[2], r[1], r[0]);
    }
    std::int32_t u;
    std::memcpy(&u, use + i, 4);
    const __m256i unused = _mm256_cmpeq_epi64(_mm256_cvtepu8_epi64(_mm_cvtsi32_si128(u)), _mm256_setzero_si256());
    const __m256d ok = _mm256_andnot_pd(_mm256_castsi256_pd(unused),
                                        _mm256_cmp_pd(_mm256_and_pd(d, abs_mask), inf, _CMP_LT_OQ));
    const int m = _mm256_movemask_pd(ok);
    const __m256i perm = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.lanes[m]));
    _mm256_storeu_pd(x + n, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(d), perm)));
    n += kPack.count[m];
    const __m256d s = _mm256_and_pd(_mm256_sub_pd(d, x04), ok);  // +0.0 in rows not used
    const __m128d s01 = _mm256_castpd256_pd128(s), s23 = _mm256_extractf128_pd(s, 1);
    sum += _mm_cvtsd_f64(s01);
    sum += _mm_cvtsd_f64(_mm_unpackhi_pd(s01, s01));
    sum += _mm_cvtsd_f64(s23);
    sum += _mm_cvtsd_f64(_mm_unpackhi_pd(s23, s23));
    lo = _mm256_min_pd(_mm256_blendv_pd(inf, d, ok), lo);  // (a < b ? a : b): the earlier of equal values
    hi = _mm256_max_pd(_mm256_blendv_pd(-inf, d, ok), hi);
  }
  alignas(32) double l[4], h[4];
  _mm256_store_pd(l, lo);
  _mm256_store_pd(h, hi);
  const double mn = std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
  const double mx = std::max(std::max(h[0], h[1]), std::max(h[2], h[3]));
  g.min = find_first_equal(x, n, mn);
  g.max = find_first_equal(x, n, mx);
  g.count = n;
  g.sum = sum;
  return i;
}
#endif

}  // namespace

Gathered gather_usable(const char* values, std::size_t rows, std::size_t stride, const std::uint8_t* use,
                       std::size_t first, double* x) {
  Gathered g;
  double x0;
  std::memcpy(&x0, values + 8 * first * stride, 8);
  std::size_t i = first;
#if defined(__x86_64__)
  if (avx2_enabled()) i = gather_rows_avx2(values, first, rows, stride, use, x0, x, g);
#endif
  gather_rows(values, i, rows, stride, use, x0, x, g);
  return g;
}

double count_windows_m2(const std::vector<double>& x, double x0, double dm, std::size_t nw, const double* lo,
                        const double* hi, WindowCount* c, std::vector<double>* const* kept, CountScratch& scratch) {
  const std::size_t n = x.size(), n_blocks = n / kBlock;
  double m2 = 0.0;
#if defined(__x86_64__)
  if (avx2_enabled()) {
    scratch.resize(n);
    if (scratch.blocks.size() < nw * n_blocks) scratch.blocks.resize(nw * n_blocks);
    std::int64_t below[kStatTargets];
    std::size_t listed[kStatTargets];
    list_blocks_avx2<true>(x.data(), n_blocks, x0, dm, m2, nw, lo, hi, below, scratch.blocks.data(), listed);
    for (std::size_t i = kBlock * n_blocks; i < n; ++i) m2 += (x[i] - x0 - dm) * (x[i] - x0 - dm);
    for (std::size_t t = 0; t < nw; ++t) {
      std::size_t k = 0;
      c[t] = classify_listed_avx2(x.data(), scratch.blocks.data() + t * n_blocks, listed[t], lo[t], hi[t],
                                  scratch.out.data(), k);
      c[t].below = below[t];
      count_rest(x.data(), kBlock * n_blocks, n, lo[t], hi[t], c[t], scratch.out.data(), k);
      c[t].inside = k;
      kept[t]->assign(scratch.out.data(), scratch.out.data() + k);
    }
    return m2;
  }
#endif
  for (const double v : x) m2 += (v - x0 - dm) * (v - x0 - dm);
  for (std::size_t t = 0; t < nw; ++t) {
    c[t] = count_window(x.data(), n, lo[t], hi[t], scratch);
    kept[t]->assign(scratch.out.data(), scratch.out.data() + c[t].inside);
  }
  return m2;
}

namespace {

// One round's partition (select_part): x[0..n)'s values below p to below[...] (which may be x
// itself), those above it to above[...], in their order; returns their counts.
std::pair<std::size_t, std::size_t> partition_generic(const double* x, std::size_t n, double p, double* below,
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

#if defined(__x86_64__)
// partition_generic four values at a time, left-packed (AVX2); each store ends at or before the
// vector just read, so below may be x.
__attribute__((target("avx2"))) std::pair<std::size_t, std::size_t> partition_avx2(const double* x, std::size_t n,
                                                                                   double p, double* below,
                                                                                   double* above) {
  const __m256d p4 = _mm256_set1_pd(p);
  std::size_t n_below = 0, n_above = 0, i = 0;
  for (; i + 4 <= n; i += 4) {
    const __m256d v = _mm256_loadu_pd(x + i);
    const int b = _mm256_movemask_pd(_mm256_cmp_pd(v, p4, _CMP_LT_OQ));
    const int a = _mm256_movemask_pd(_mm256_cmp_pd(v, p4, _CMP_GT_OQ));
    const __m256 f = _mm256_castpd_ps(v);
    const __m256i to_below = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.lanes[b]));
    const __m256i to_above = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.lanes[a]));
    _mm256_storeu_pd(below + n_below, _mm256_castps_pd(_mm256_permutevar8x32_ps(f, to_below)));
    _mm256_storeu_pd(above + n_above, _mm256_castps_pd(_mm256_permutevar8x32_ps(f, to_above)));
    n_below += kPack.count[b];
    n_above += kPack.count[a];
  }
  const auto rest = partition_generic(x + i, n - i, p, below + n_below, above + n_above);
  return {n_below + rest.first, n_above + rest.second};
}
#endif

// select_order_statistics on x[0..n), whose ranks are base + 0 .. n - 1 of the whole, for the
// ranks [r, r_end) among them. Each round: the median of three values as the pivot; the values
// below it stored in place (never past the one read), those above it to `above` and back after the
// pivot's copies, so that x reads [below][p ... p][above]; the part below recursively, the part
// above in the loop. Runs of unlucky pivots, short parts and a zero pivot end in std::sort.
void select_part(double* x, std::size_t n, std::size_t base, const std::size_t* r, const std::size_t* r_end,
                 double* above, int depth) {
  while (r != r_end) {
    // A zero pivot: its copies' bits may differ (-0.0, +0.0) and must not be overwritten.
    const double a = x[n / 4], b = x[n / 2], c = x[3 * n / 4];
    const double p = std::max(std::min(a, b), std::min(std::max(a, b), c));
    if (n <= 16 || depth > 64 || p == 0.0) {
      std::sort(x, x + n);
      return;
    }
    ++depth;
#if defined(__x86_64__)
    const auto [n_below, n_above] = avx2_enabled() ? partition_avx2(x, n, p, x, above)
                                                   : partition_generic(x, n, p, x, above);
#else
    const auto [n_below, n_above] = partition_generic(x, n, p, x, above);
#endif
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

// Quickselect by three-way partitions that do not branch on the values: std::nth_element's
// partitions mispredict about every other comparison, which made narrowing a window rank 0's
// largest statistics cost in small campaigns.
void select_order_statistics(double* x, std::size_t n, const std::size_t* r, std::size_t k) {
  thread_local std::vector<double> above;
  if (above.size() < n) above.resize(n);
  select_part(x, n, 0, r, r + k, above.data(), 0);
}

bool use_avx2_kernels(bool on) {
  avx2_enabled() = on && has_avx2();
  return avx2_enabled();
}

}  // namespace truss::sampling
