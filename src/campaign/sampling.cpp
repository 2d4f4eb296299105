// sampling.cpp — distributions, sampling plans and Sobol' indices for
// uncertainty campaigns. See sampling.hpp for the API and the references; the
// comments here explain the choices that are not obvious from the code.
#include "campaign/sampling.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::campaign {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Probability mass below which a truncated normal is rejected: its quantile
// would be computed from differences of tail probabilities that carry no
// meaningful digits, and such an input is almost certainly a units mistake.
constexpr double kMinTruncatedMass = 1e-12;

// Feistel rounds of the Latin hypercube permutation. Luby and Rackoff show 4
// rounds of a pseudorandom function give a strong pseudorandom permutation;
// 6 costs little and removes any visible structure for tiny domains (n < 16).
constexpr int kFeistelRounds = 6;

// Sobol' points are 32-bit binary fractions (enough for 2^32 runs); the
// digital shift is applied on 53 bits so the 21 low digits become random.
constexpr int kSobolBits = 32;

// ---------------------------------------------------------------------------
// Truncated normal: probabilities in the form that keeps relative accuracy.
// ---------------------------------------------------------------------------

// Retained mass Phi(beta) - Phi(alpha) computed without cancellation: both
// bounds in the same tail use that tail's small probabilities.
double truncated_mass(double alpha, double beta) {
  if (beta <= 0.0) return normal_cdf(beta) - normal_cdf(alpha);
  if (alpha >= 0.0) return normal_cdf(-alpha) - normal_cdf(-beta);
  return 1.0 - normal_cdf(alpha) - normal_cdf(-beta);
}

// ---------------------------------------------------------------------------
// Sobol' direction numbers (Joe & Kuo), expanded once to 32 bits per dimension.
// ---------------------------------------------------------------------------

constexpr std::uint16_t kJoeKuoRows[] = {
#include "campaign/sobol_directions.inc"
};

// Table [dim * 32 + k] = V_(k+1) of Joe-Kuo dimension dim + 1, scaled by 2^32.
const std::vector<std::uint32_t>& sobol_table() {
  static const std::vector<std::uint32_t> table = [] {
    std::vector<std::uint32_t> v(static_cast<std::size_t>(kSobolMaxDims) * kSobolBits);
    // Dimension 1: all m_k = 1, i.e. the van der Corput sequence.
    for (int k = 0; k < kSobolBits; ++k) v[static_cast<std::size_t>(k)] = 1u << (31 - k);
    std::size_t pos = 0;
    for (int dim = 1; dim < kSobolMaxDims; ++dim) {
      std::uint32_t* V = v.data() + static_cast<std::size_t>(dim) * kSobolBits - 1;  // V[1..32]
      const unsigned s = kJoeKuoRows[pos++];
      const unsigned a = kJoeKuoRows[pos++];
      for (unsigned i = 1; i <= s; ++i) V[i] = static_cast<std::uint32_t>(kJoeKuoRows[pos++]) << (32 - i);
      // Recurrence of Bratley & Fox (1988) in the form of Joe & Kuo's sobol.cc:
      // V_i = V_(i-s) ^ (V_(i-s) >> s) ^ XOR_k a_k V_(i-k).
      for (unsigned i = s + 1; i <= static_cast<unsigned>(kSobolBits); ++i) {
        V[i] = V[i - s] ^ (V[i - s] >> s);
        for (unsigned k = 1; k + 1 <= s; ++k)
          if ((a >> (s - 1 - k)) & 1u) V[i] ^= V[i - k];
      }
    }
    if (pos != std::size(kJoeKuoRows))
      throw std::logic_error("sobol_directions.inc: row count does not match kSobolMaxDims");
    return v;
  }();
  return table;
}

// Balanced Feistel network on 2 * half_bits bits (half_bits in [1, 32]): a
// bijection whatever the round function, here SplitMix64 keyed per round.
std::uint64_t feistel(std::uint64_t x, int half_bits, const std::uint64_t* round_keys) {
  const std::uint64_t mask = (1ULL << half_bits) - 1;
  std::uint64_t left = x >> half_bits;
  std::uint64_t right = x & mask;
  for (int r = 0; r < kFeistelRounds; ++r) {
    const std::uint64_t f = splitmix_at(round_keys[r], right) & mask;
    const std::uint64_t next = left ^ f;
    left = right;
    right = next;
  }
  return (left << half_bits) | right;
}

// AS 241 (PPND16) coefficients, lowest degree first: A/B for |p - 0.5| <=
// 0.425, C/D for r = sqrt(-log(min(p, 1-p))) <= 5, E/F beyond.
// clang-format off
constexpr std::array<double, 8> kAs241A = {
    3.3871328727963666080e0, 1.3314166789178437745e+2, 1.9715909503065514427e+3, 1.3731693765509461125e+4,
    4.5921953931549871457e+4, 6.7265770927008700853e+4, 3.3430575583588128105e+4, 2.5090809287301226727e+3};
constexpr std::array<double, 8> kAs241B = {
    1.0, 4.2313330701600911252e+1, 6.8718700749205790830e+2, 5.3941960214247511077e+3,
    2.1213794301586595867e+4, 3.9307895800092710610e+4, 2.8729085735721942674e+4, 5.2264952788528545610e+3};
constexpr std::array<double, 8> kAs241C = {
    1.42343711074968357734e0, 4.63033784615654529590e0, 5.76949722146069140550e0, 3.64784832476320460504e0,
    1.27045825245236838258e0, 2.41780725177450611770e-1, 2.27238449892691845833e-2, 7.74545014278341407640e-4};
constexpr std::array<double, 8> kAs241D = {
    1.0, 2.05319162663775882187e0, 1.67638483018380384940e0, 6.89767334985100004550e-1,
    1.48103976427480074590e-1, 1.51986665636164571966e-2, 5.47593808499534494600e-4, 1.05075007164441684324e-9};
constexpr std::array<double, 8> kAs241E = {
    6.65790464350110377720e0, 5.46378491116411436990e0, 1.78482653991729133580e0, 2.96560571828504891230e-1,
    2.65321895265761230930e-2, 1.24266094738807843860e-3, 2.71155556874348757815e-5, 2.01033439929228813265e-7};
constexpr std::array<double, 8> kAs241F = {
    1.0, 5.99832206555887937690e-1, 1.36929880922735805310e-1, 1.48753612908506148525e-2,
    7.86869131145613259100e-4, 1.84631831751005468180e-5, 1.42151175831644588870e-7, 2.04426310338993978564e-15};
// clang-format on

// c[0] + c[1] r + ... + c[7] r^7 by Horner's rule, highest degree first as
// in Wichura's Fortran, so the rounding sequence is the published one.
double horner8(const std::array<double, 8>& c, double r) {
  double v = c[7];
  for (int k = 6; k >= 0; --k) v = v * r + c[static_cast<std::size_t>(k)];
  return v;
}

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
// Standard normal
// ===========================================================================

double normal_cdf(double x) {
  // erfc keeps relative accuracy for large arguments, so the lower tail is
  // accurate down to underflow; 1 - 0.5*erfc(...) would lose it.
  return 0.5 * std::erfc(-x * 0.70710678118654752440);
}

double normal_quantile(double p) {
  // Wichura (1988), AS 241, PPND16: rational approximations in three
  // regions, relative accuracy about 1e-16.
  if (std::isnan(p) || p < 0.0 || p > 1.0) return kNaN;
  if (p == 0.0) return -kInf;
  if (p == 1.0) return kInf;

  const double q = p - 0.5;
  if (std::fabs(q) <= 0.425) {
    const double r = 0.180625 - q * q;
    return q * horner8(kAs241A, r) / horner8(kAs241B, r);
  }
  // Tail: r = sqrt(-log(min(p, 1-p))). For p > 0.5 the subtraction 1 - p is
  // exact (Sterbenz), so the upper tail is as accurate as p allows.
  double r = std::sqrt(-std::log(q < 0.0 ? p : 1.0 - p));
  double val;
  if (r <= 5.0) {
    r -= 1.6;
    val = horner8(kAs241C, r) / horner8(kAs241D, r);
  } else {
    r -= 5.0;
    val = horner8(kAs241E, r) / horner8(kAs241F, r);
  }
  return q < 0.0 ? -val : val;
}

// ===========================================================================
// Distributions
// ===========================================================================

Distribution Distribution::normal(double mean, double std) {
  Distribution d;
  d.kind = DistributionKind::normal;
  d.mean = mean;
  d.std = std;
  return d;
}

Distribution Distribution::truncated_normal(double mean, double std, double lower, double upper) {
  Distribution d;
  d.kind = DistributionKind::truncated_normal;
  d.mean = mean;
  d.std = std;
  d.lower = lower;
  d.upper = upper;
  return d;
}

Distribution Distribution::uniform(double lower, double upper) {
  Distribution d;
  d.kind = DistributionKind::uniform;
  d.lower = lower;
  d.upper = upper;
  return d;
}

Distribution Distribution::lognormal(double mu, double sigma) {
  Distribution d;
  d.kind = DistributionKind::lognormal;
  d.mu = mu;
  d.sigma = sigma;
  return d;
}

Distribution Distribution::lognormal_from_median(double median, double sigma) {
  // log of a non-positive median is NaN or -inf, which validate() reports on mu.
  return lognormal(median > 0.0 ? std::log(median) : kNaN, sigma);
}

Distribution Distribution::discrete(std::vector<double> values, std::vector<double> weights) {
  Distribution d;
  d.kind = DistributionKind::discrete;
  if (values.size() == weights.size()) {
    // The quantile is "smallest value with cumulative weight >= u", which
    // is an inverse CDF only for ascending values; sort the pairs here so
    // callers may list them in any order.
    std::vector<std::size_t> order(values.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
    for (std::size_t i : order) {
      d.values.push_back(values[i]);
      d.weights.push_back(weights[i]);
    }
  } else {
    d.values = std::move(values);
    d.weights = std::move(weights);
  }
  return d;
}

std::string Distribution::validate() const {
  switch (kind) {
    case DistributionKind::normal:
    case DistributionKind::truncated_normal: {
      if (!std::isfinite(mean)) return fmt::format("mean: must be finite (got {})", mean);
      if (!(std > 0.0) || !std::isfinite(std))
        return fmt::format("std: must be > 0 and finite (got {})", std);
      if (kind == DistributionKind::normal) return {};
      if (std::isnan(lower)) return "lower: must not be NaN";
      if (std::isnan(upper)) return "upper: must not be NaN";
      if (!(lower < upper))
        return fmt::format("lower: must be < upper (got lower {}, upper {})", lower, upper);
      const double mass = truncated_mass((lower - mean) / std, (upper - mean) / std);
      if (!(mass >= kMinTruncatedMass))
        return fmt::format(
            "lower: truncation to [{}, {}] excludes all probability mass of normal(mean {}, std {}) "
            "(retained mass {:.3g} < {:g})",
            lower, upper, mean, std, mass, kMinTruncatedMass);
      return {};
    }
    case DistributionKind::uniform:
      if (!std::isfinite(lower)) return fmt::format("lower: must be finite (got {})", lower);
      if (!std::isfinite(upper)) return fmt::format("upper: must be finite (got {})", upper);
      if (!(lower < upper))
        return fmt::format("lower: must be < upper (got lower {}, upper {})", lower, upper);
      if (!std::isfinite(upper - lower)) return fmt::format("upper: range upper - lower overflows");
      return {};
    case DistributionKind::lognormal:
      if (!std::isfinite(mu)) return fmt::format("mu: must be finite (mu = log(median); got {})", mu);
      if (!(sigma > 0.0) || !std::isfinite(sigma))
        return fmt::format("sigma: must be > 0 and finite (got {})", sigma);
      return {};
    case DistributionKind::discrete: {
      if (values.empty()) return "values: must not be empty";
      if (weights.size() != values.size())
        return fmt::format("weights: has {} entries but values has {}", weights.size(), values.size());
      double total = 0.0;
      for (std::size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i]))
          return fmt::format("values: values[{}] = {} is not finite", i, values[i]);
        if (i > 0 && !(values[i - 1] < values[i]))
          return fmt::format("values: must be distinct and increasing (values[{}] = {} after {})", i,
                             values[i], values[i - 1]);
        if (!(weights[i] > 0.0) || !std::isfinite(weights[i]))
          return fmt::format("weights: must be positive and finite (weights[{}] = {})", i, weights[i]);
        total += weights[i];
      }
      if (!std::isfinite(total)) return "weights: sum overflows";
      return {};
    }
  }
  return "kind: unknown distribution kind";
}

double Distribution::calc_quantile(double u) const {
  switch (kind) {
    case DistributionKind::normal:
      return mean + std * normal_quantile(u);
    case DistributionKind::truncated_normal: {
      const double alpha = (lower - mean) / std;
      const double beta = (upper - mean) / std;
      const double mass = truncated_mass(alpha, beta);
      // Invert in the tail where the target lies: lower-tail probabilities
      // left of the mode, upper-tail (complementary) ones right of it. With
      // the interval deep in the right tail, Phi(alpha) + u*mass would be
      // 1 - tiny and lose every digit of the tiny part.
      const double p = normal_cdf(alpha) + u * mass;
      double z;
      if (p <= 0.5) {
        z = normal_quantile(p);
      } else {
        const double q = normal_cdf(-beta) + (1.0 - u) * mass;
        z = -normal_quantile(q);
      }
      // Rounding can step a hair outside the interval at its ends.
      return std::clamp(mean + std * z, lower, upper);
    }
    case DistributionKind::uniform:
      return std::clamp(lower + u * (upper - lower), lower, upper);
    case DistributionKind::lognormal:
      return std::exp(mu + sigma * normal_quantile(u));
    case DistributionKind::discrete: {
      double total = 0.0;
      for (double w : weights) total += w;
      const double target = u * total;
      double cum = 0.0;
      for (std::size_t i = 0; i < values.size(); ++i) {
        cum += weights[i];
        if (cum >= target) return values[i];
      }
      // Only reachable through rounding of the running sum against u*total.
      return values.empty() ? kNaN : values.back();
    }
  }
  return kNaN;
}

// ===========================================================================
// SamplePlan
// ===========================================================================

SamplePlan::SamplePlan(SamplingMethod method, std::int64_t n_runs, int d, std::uint64_t master_seed)
    : method_(method), n_runs_(n_runs), d_(d), seed_(master_seed) {
  valid_ = validate().empty();
  if (!valid_) return;

  const auto nd = static_cast<std::size_t>(d_);
  switch (method_) {
    case SamplingMethod::monte_carlo:
      break;
    case SamplingMethod::latin_hypercube: {
      // Balanced Feistel network on 2h bits with 2^(2h) >= n: cycle walking
      // then needs fewer than 4 expected steps (the domain is < 4n).
      const int bits = std::bit_width(static_cast<std::uint64_t>(n_runs_ - 1));
      half_bits_ = (bits + 1) / 2;
      round_keys_.resize(nd * kFeistelRounds);
      // Round keys depend only on (seed, dimension): the permutation of a
      // dimension is fixed before any run is computed.
      for (std::size_t j = 0; j < nd; ++j)
        for (int r = 0; r < kFeistelRounds; ++r)
          round_keys_[j * kFeistelRounds + static_cast<std::size_t>(r)] =
              counter_hash(seed_, r, static_cast<std::int64_t>(j), kTagLhsPerm);
      break;
    }
    case SamplingMethod::sobol:
    case SamplingMethod::saltelli: {
      std::int64_t n_points = n_runs_;
      if (method_ == SamplingMethod::saltelli) {
        if (!saltelli_uses_sobol()) break;
        n_points = saltelli_base_count();
      }
      sobol_dims_ = (method_ == SamplingMethod::saltelli) ? 2 * d_ : d_;
      const auto ns = static_cast<std::size_t>(sobol_dims_);
      // Only the bits that Gray codes of indices < n_points can set.
      const int nbits =
          std::max(1, static_cast<int>(std::bit_width(static_cast<std::uint64_t>(n_points - 1))));
      const auto& table = sobol_table();
      directions_.resize(static_cast<std::size_t>(nbits) * ns);
      for (int k = 0; k < nbits; ++k)
        for (std::size_t j = 0; j < ns; ++j)
          directions_[static_cast<std::size_t>(k) * ns + j] =
              table[j * kSobolBits + static_cast<std::size_t>(k)];
      // Random digital shift (XOR) on 53 binary digits. Bit 0 is forced to
      // 1: unshifted points have zeros beyond digit 32, so every shifted
      // point is an odd multiple of 2^-53 and never exactly 0 (nor 1). The
      // shift is a bijection on each dyadic interval level, so the net
      // (stratification) properties of the first 32 digits are preserved.
      shifts_.resize(ns);
      for (std::size_t j = 0; j < ns; ++j)
        shifts_[j] = (counter_hash(seed_, 0, static_cast<std::int64_t>(j), kTagSobolShift) >> 11) | 1u;
      break;
    }
  }
}

std::int64_t SamplePlan::saltelli_base_count() const {
  if (method_ != SamplingMethod::saltelli || d_ < 1) return 0;
  return n_runs_ / saltelli_block(d_);
}

std::string SamplePlan::validate() const {
  if (n_runs_ < 1) return fmt::format("n_runs: must be >= 1 (got {})", n_runs_);
  if (d_ < 0) return fmt::format("d: must be >= 0 (got {})", d_);
  switch (method_) {
    case SamplingMethod::monte_carlo:
      return {};
    case SamplingMethod::latin_hypercube:
      // Stratum indices must be exact in a double.
      if (n_runs_ > (std::int64_t{1} << 53))
        return fmt::format("n_runs: latin_hypercube supports at most 2^53 runs (got {})", n_runs_);
      return {};
    case SamplingMethod::sobol:
      if (d_ > kSobolMaxDims)
        return fmt::format(
            "d: sobol supports at most {} dimensions (Joe-Kuo direction numbers embedded up to "
            "dimension {}); got {}",
            kSobolMaxDims, kSobolMaxDims, d_);
      if (n_runs_ > (std::int64_t{1} << kSobolBits))
        return fmt::format("n_runs: sobol supports at most 2^{} runs (got {})", kSobolBits, n_runs_);
      return {};
    case SamplingMethod::saltelli: {
      if (d_ < 1) return fmt::format("d: saltelli needs d >= 1 (got {})", d_);
      const std::int64_t block = saltelli_block(d_);
      if (n_runs_ % block != 0) {
        const std::int64_t below = n_runs_ / block;
        const std::int64_t above = below + 1;
        if (below == 0)
          return fmt::format(
              "n_runs: saltelli needs a multiple of d + 2 = {} (blocks A, B, AB_1..AB_{}); "
              "got {}, nearest valid count is {} (N = 1)",
              block, d_, n_runs_, block);
        return fmt::format(
            "n_runs: saltelli needs a multiple of d + 2 = {} (blocks A, B, AB_1..AB_{}); got {}, "
            "nearest valid counts are {} (N = {}) and {} (N = {})",
            block, d_, n_runs_, below * block, below, above * block, above);
      }
      if (saltelli_uses_sobol() && n_runs_ / block > (std::int64_t{1} << kSobolBits))
        return fmt::format("n_runs: saltelli with a Sobol' base supports at most 2^{} blocks (got {})",
                           kSobolBits, n_runs_ / block);
      return {};
    }
  }
  return "method: unknown sampling method";
}

double SamplePlan::sobol_point_unshifted(std::uint32_t index, int dim) {
  if (dim < 0 || dim >= kSobolMaxDims)
    throw std::out_of_range(fmt::format("sobol_point_unshifted: dim {} outside [0, {})", dim, kSobolMaxDims));
  const std::uint32_t* V = sobol_table().data() + static_cast<std::size_t>(dim) * kSobolBits;
  std::uint32_t g = index ^ (index >> 1);
  std::uint32_t x = 0;
  for (int k = 0; g != 0; ++k, g >>= 1)
    if (g & 1u) x ^= V[k];
  return static_cast<double>(x) * 0x1p-32;
}

// Coordinates [first, first + count) of Sobol' point `index` as 32-bit
// integers. The point is the XOR of the direction numbers selected by the
// bits of the Gray code of the index (Antonov & Saleev 1979), which gives
// any index directly, with no state carried from previous runs.
void SamplePlan::calc_sobol(std::uint64_t index, int first, int count, std::uint32_t* x) const {
  std::fill(x, x + count, 0u);
  const auto ns = static_cast<std::size_t>(sobol_dims_);
  std::uint64_t g = index ^ (index >> 1);
  for (std::size_t k = 0; g != 0; ++k, g >>= 1) {
    if (!(g & 1u)) continue;
    const std::uint32_t* row = directions_.data() + k * ns + static_cast<std::size_t>(first);
    for (int j = 0; j < count; ++j) x[j] ^= row[j];
  }
}

void SamplePlan::calc_uniforms(std::int64_t run_index, double* u) const {
  if (!valid_) throw std::logic_error("SamplePlan::calc_uniforms on an invalid plan: " + validate());
  if (run_index < 0 || run_index >= n_runs_)
    throw std::out_of_range(
        fmt::format("SamplePlan::calc_uniforms: run_index {} outside [0, {})", run_index, n_runs_));

  switch (method_) {
    case SamplingMethod::monte_carlo: {
      const std::uint64_t state = counter_run_state(seed_, run_index, kTagMonteCarlo);
      for (int j = 0; j < d_; ++j) u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(j)));
      return;
    }
    case SamplingMethod::latin_hypercube: {
      const std::uint64_t jitter_state = counter_run_state(seed_, run_index, kTagLhsJitter);
      const auto n = static_cast<std::uint64_t>(n_runs_);
      const double dn = static_cast<double>(n_runs_);
      for (int j = 0; j < d_; ++j) {
        const std::uint64_t* keys = round_keys_.data() + static_cast<std::size_t>(j) * kFeistelRounds;
        // Cycle walking: re-apply the bijection on [0, 2^2h) until the
        // value lands in [0, n); this restricts it to a bijection on [0, n).
        std::uint64_t stratum = static_cast<std::uint64_t>(run_index);
        if (n > 1) {
          do stratum = feistel(stratum, half_bits_, keys);
          while (stratum >= n);
        }
        const double jitter = to_open_unit(splitmix_at(jitter_state, static_cast<std::uint64_t>(j)));
        const double s = static_cast<double>(stratum);
        double v = (s + jitter) / dn;
        // s + jitter rounds up to s + 1 when jitter is within an ulp of 1;
        // keep the sample inside its stratum [s/n, (s+1)/n) and below 1.
        const double hi = (s + 1.0) / dn;
        if (v >= hi) v = std::nextafter(hi, 0.0);
        u[j] = v;
      }
      return;
    }
    case SamplingMethod::sobol: {
      // Run r is Sobol' point r: the origin is NOT dropped. The digital shift
      // already moves it away from 0, and dropping it would break the
      // balance of every block of 2^m points (Owen, "On dropping the first
      // Sobol' point", arXiv:2008.08051): with points 1..2^m the first
      // interval [0, 2^-m) of each coordinate is empty and another holds two.
      constexpr int kChunk = 256;
      std::array<std::uint32_t, kChunk> x{};
      for (int first = 0; first < d_; first += kChunk) {
        const int count = std::min(kChunk, d_ - first);
        calc_sobol(static_cast<std::uint64_t>(run_index), first, count, x.data());
        for (int j = 0; j < count; ++j) {
          const std::uint64_t z = (static_cast<std::uint64_t>(x[static_cast<std::size_t>(j)]) << 21) ^
                                  shifts_[static_cast<std::size_t>(first + j)];
          u[first + j] = static_cast<double>(z) * 0x1p-53;
        }
      }
      return;
    }
    case SamplingMethod::saltelli: {
      // Block b = base point b in 2d dimensions: A = its first d
      // coordinates, B = the last d. Position 0 -> A, 1 -> B, 2 + i -> AB_i
      // (A with column i taken from B).
      const int block = saltelli_block(d_);
      const std::int64_t b = run_index / block;
      const int pos = static_cast<int>(run_index % block);
      const int from = (pos == 1) ? d_ : 0;  // columns [from, from + d) of the base point
      const int swapped = pos >= 2 ? pos - 2 : -1;
      if (saltelli_uses_sobol()) {
        auto coord = [&](std::uint32_t xi, int col) {
          const std::uint64_t z =
              (static_cast<std::uint64_t>(xi) << 21) ^ shifts_[static_cast<std::size_t>(col)];
          return static_cast<double>(z) * 0x1p-53;
        };
        constexpr int kChunk = 256;
        std::array<std::uint32_t, kChunk> x{};
        for (int first = 0; first < d_; first += kChunk) {
          const int count = std::min(kChunk, d_ - first);
          calc_sobol(static_cast<std::uint64_t>(b), from + first, count, x.data());
          for (int j = 0; j < count; ++j)
            u[first + j] = coord(x[static_cast<std::size_t>(j)], from + first + j);
        }
        if (swapped >= 0) {
          std::uint32_t xb = 0;
          calc_sobol(static_cast<std::uint64_t>(b), d_ + swapped, 1, &xb);
          u[swapped] = coord(xb, d_ + swapped);
        }
      } else {
        const std::uint64_t state = counter_run_state(seed_, b, kTagSaltelliMc);
        for (int j = 0; j < d_; ++j)
          u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(from + j)));
        if (swapped >= 0)
          u[swapped] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(d_ + swapped)));
      }
      return;
    }
  }
}

void SamplePlan::calc_values(std::int64_t run_index, std::span<const Distribution> dists, double* x) const {
  if (dists.size() != static_cast<std::size_t>(d_))
    throw std::invalid_argument(
        fmt::format("SamplePlan::calc_values: {} distributions for a plan of d = {}", dists.size(), d_));
  calc_uniforms(run_index, x);
  for (std::size_t j = 0; j < dists.size(); ++j) x[j] = dists[j].calc_quantile(x[j]);
}

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

}  // namespace truss::campaign
