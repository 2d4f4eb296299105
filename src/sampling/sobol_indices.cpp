// sobol_indices.cpp — Sobol' first-order and total indices from a Saltelli design (Saltelli 2010),
// with bootstrap intervals. Split from sampling.cpp; see sampling.hpp for the API.
#include "sampling/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::sampling {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Percentile of sorted data by linear interpolation between order statistics
// (Hyndman & Fan type 7, the default of R and NumPy).
double sorted_quantile(const std::vector<double>& sorted, double p) {
  const double h = (static_cast<double>(sorted.size()) - 1.0) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

}  // namespace

// ===========================================================================
// Sobol' indices (Saltelli 2010)
// ===========================================================================

namespace {

struct IndexEstimate {
  double mean = 0.0;
  double variance = 0.0;
  std::vector<double> s1, st;
};

// Estimates over the blocks pick[0..N) (identity for the point estimate, a
// resample for the bootstrap). `shift` is the full-sample mean, subtracted
// before accumulating squares so the one-pass variance does not cancel.
void estimate_indices(std::span<const double> y, int d, std::span<const std::int64_t> pick, double shift,
                      IndexEstimate& out) {
  const int block = d + 2;
  const auto n = static_cast<double>(pick.size());
  const auto nd = static_cast<std::size_t>(d);
  std::fill(out.s1.begin(), out.s1.end(), 0.0);
  std::fill(out.st.begin(), out.st.end(), 0.0);
  double sum = 0.0, sum2 = 0.0;
  for (std::int64_t k : pick) {
    const double* row = y.data() + k * block;
    const double fa = row[0] - shift;
    const double fb = row[1] - shift;
    sum += fa + fb;
    sum2 += fa * fa + fb * fb;
    for (std::size_t i = 0; i < nd; ++i) {
      const double fab = row[2 + i] - shift;
      // Saltelli et al. (2010), Table 2: V_i ~ mean f(B) (f(AB_i) - f(A)), on
      // outputs centred by the mean of f(A) and f(B) (as SALib does). The
      // estimator is unbiased either way, but its variance grows with the
      // squared mean: for the motor campaign's peak pin force (mean 0.83 N,
      // std 1.1e-4 N, 88 blocks) it gave S_i = 242 and 351 uncentred, 0.48
      // and 0.46 centred.
      out.s1[i] += fb * (fab - fa);
      // Jansen (1999), recommended in the same table:
      // E_(~i) ~ mean (f(A) - f(AB_i))^2 / 2.
      out.st[i] += (fa - fab) * (fa - fab);
    }
  }
  const double m = sum / (2.0 * n);
  out.mean = shift + m;
  out.variance = sum2 / (2.0 * n) - m * m;
  for (std::size_t i = 0; i < nd; ++i) {
    out.s1[i] = out.s1[i] / n / out.variance;
    out.st[i] = out.st[i] / (2.0 * n) / out.variance;
  }
}

}  // namespace

SobolIndices calc_sobol_indices(std::span<const double> y, int d, std::uint64_t bootstrap_seed,
                                int n_resamples, double confidence) {
  if (d < 1) throw std::invalid_argument(fmt::format("calc_sobol_indices: d must be >= 1 (got {})", d));
  const auto block = static_cast<std::size_t>(SamplePlan::saltelli_block(d));
  if (y.size() % block != 0)
    throw std::invalid_argument(
        fmt::format("calc_sobol_indices: {} outputs is not a multiple of d + 2 = {}", y.size(), block));
  const auto n_base = static_cast<std::int64_t>(y.size() / block);
  if (n_base < 2)
    throw std::invalid_argument(fmt::format("calc_sobol_indices: need at least 2 blocks (got {})", n_base));
  if (n_resamples < 0)
    throw std::invalid_argument(
        fmt::format("calc_sobol_indices: n_resamples must be >= 0 (got {})", n_resamples));
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument(
        fmt::format("calc_sobol_indices: confidence must be in (0, 1) (got {})", confidence));
  for (std::size_t k = 0; k < y.size(); ++k)
    if (!std::isfinite(y[k]))
      throw std::invalid_argument(fmt::format("calc_sobol_indices: y[{}] = {} is not finite", k, y[k]));

  const auto nd = static_cast<std::size_t>(d);
  double shift = 0.0;
  for (std::int64_t k = 0; k < n_base; ++k)
    shift += y[static_cast<std::size_t>(k) * block] + y[static_cast<std::size_t>(k) * block + 1];
  shift /= 2.0 * static_cast<double>(n_base);

  std::vector<std::int64_t> pick(static_cast<std::size_t>(n_base));
  for (std::int64_t k = 0; k < n_base; ++k) pick[static_cast<std::size_t>(k)] = k;
  IndexEstimate est;
  est.s1.resize(nd);
  est.st.resize(nd);
  estimate_indices(y, d, pick, shift, est);

  SobolIndices res;
  res.d = d;
  res.n_base = n_base;
  res.mean = est.mean;
  res.variance = est.variance;
  res.first_order = est.s1;
  res.total = est.st;
  res.n_resamples = n_resamples;
  res.confidence = confidence;
  res.first_order_lo.assign(nd, kNaN);
  res.first_order_hi.assign(nd, kNaN);
  res.total_lo.assign(nd, kNaN);
  res.total_hi.assign(nd, kNaN);
  if (n_resamples == 0 || !(est.variance > 0.0)) return res;

  // Percentile bootstrap over blocks: a block (A, B, AB_1..AB_d of one base
  // point) is the unit of independence of the design, so blocks are
  // resampled whole. Draw k of resample r is keyed by (seed, r, k).
  std::vector<std::vector<double>> s1_boot(nd, std::vector<double>(static_cast<std::size_t>(n_resamples)));
  std::vector<std::vector<double>> st_boot(nd, std::vector<double>(static_cast<std::size_t>(n_resamples)));
  const double dn = static_cast<double>(n_base);
  IndexEstimate boot;
  boot.s1.resize(nd);
  boot.st.resize(nd);
  for (int r = 0; r < n_resamples; ++r) {
    const std::uint64_t state = counter_run_state(bootstrap_seed, r, kTagBootstrap);
    for (std::int64_t k = 0; k < n_base; ++k) {
      const double uu = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(k)));
      pick[static_cast<std::size_t>(k)] = std::min(static_cast<std::int64_t>(uu * dn), n_base - 1);
    }
    estimate_indices(y, d, pick, shift, boot);
    for (std::size_t i = 0; i < nd; ++i) {
      s1_boot[i][static_cast<std::size_t>(r)] = boot.s1[i];
      st_boot[i][static_cast<std::size_t>(r)] = boot.st[i];
    }
  }
  const double p_lo = 0.5 * (1.0 - confidence);
  const double p_hi = 0.5 * (1.0 + confidence);
  // A resample whose outputs are all equal has V = 0 and NaN indices; drop
  // those (NaN would also break the ordering std::sort needs).
  auto interval = [&](std::vector<double>& boot, double& lo, double& hi) {
    boot.erase(std::remove_if(boot.begin(), boot.end(), [](double v) { return !std::isfinite(v); }),
               boot.end());
    if (boot.empty()) return;
    std::sort(boot.begin(), boot.end());
    lo = sorted_quantile(boot, p_lo);
    hi = sorted_quantile(boot, p_hi);
  };
  for (std::size_t i = 0; i < nd; ++i) {
    interval(s1_boot[i], res.first_order_lo[i], res.first_order_hi[i]);
    interval(st_boot[i], res.total_lo[i], res.total_hi[i]);
  }
  return res;
}

}  // namespace truss::sampling
