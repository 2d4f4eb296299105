// distributions.cpp — the uncertain inputs of a campaign: standard normal CDF and quantile (AS 241)
// and the Distribution kinds. Split from sampling.cpp; see sampling.hpp for the API.
#include "sampling/sampling.hpp"
#include "sampling/simd_clones.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::sampling {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// Probability mass below which a truncated normal is rejected: its quantile
// would be computed from differences of tail probabilities that carry no
// meaningful digits, and such an input is almost certainly a units mistake.
constexpr double kMinTruncatedMass = 1e-12;

// Retained mass Phi(beta) - Phi(alpha) computed without cancellation: both
// bounds in the same tail use that tail's small probabilities.
double truncated_mass(double alpha, double beta) {
  if (beta <= 0.0) return normal_cdf(beta) - normal_cdf(alpha);
  if (alpha >= 0.0) return normal_cdf(-alpha) - normal_cdf(-beta);
  return 1.0 - normal_cdf(alpha) - normal_cdf(-beta);
}
// ---------------------------------------------------------------------------
// Truncated normal: probabilities in the form that keeps relative accuracy.
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

// z[i] = normal_quantile(p[i]) where |p[i] - 0.5| <= 0.425 (AS 241's central region, most
// draws), the same operations in the same order; other entries get a value to be replaced. One
// loop with no branch: it vectorises.
TRUSS_SAMPLING_CLONES
void normal_quantiles_central(const double* p, double* z, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const double q = p[i] - 0.5;
    const double r = 0.180625 - q * q;
    z[i] = q * horner8(kAs241A, r) / horner8(kAs241B, r);
  }
}

}  // namespace

// The central region in one vectorised pass, the tails one at a time (sampling.hpp).
void normal_quantiles(const double* p, double* z, std::size_t count) {
  constexpr std::size_t kChunk = 64;
  double central[kChunk];
  std::size_t tails[kChunk];
  for (std::size_t i0 = 0; i0 < count; i0 += kChunk) {
    const std::size_t m = std::min(kChunk, count - i0);
    normal_quantiles_central(p + i0, central, m);
    // The tails (about 15 % of the draws, at random), and anything outside (0, 1), listed without
    // a branch and then computed one at a time: no misprediction between them.
    std::size_t n_tails = 0;
    for (std::size_t i = 0; i < m; ++i) {
      tails[n_tails] = i;
      n_tails += !(std::fabs(p[i0 + i] - 0.5) <= 0.425);
    }
    for (std::size_t t = 0; t < n_tails; ++t) central[tails[t]] = normal_quantile(p[i0 + tails[t]]);
    std::copy(central, central + m, z + i0);
  }
}

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
      if (values.empty()) return "values: must not be empty (the table of values a draw takes)";
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

double Distribution::calc_normal_score(double x) const {
  switch (kind) {
    case DistributionKind::normal:
      return (x - mean) / std;
    case DistributionKind::truncated_normal: {
      const double alpha = (lower - mean) / std, beta = (upper - mean) / std, t = (x - mean) / std;
      const double mass = truncated_mass(alpha, beta);
      // As calc_quantile: the lower tail's probability left of the mode, the upper tail's right of it.
      if (t <= 0.0) return normal_quantile(std::clamp((normal_cdf(t) - normal_cdf(alpha)) / mass, 0.0, 1.0));
      return -normal_quantile(std::clamp((normal_cdf(-t) - normal_cdf(-beta)) / mass, 0.0, 1.0));
    }
    case DistributionKind::uniform:
      return normal_quantile(std::clamp((x - lower) / (upper - lower), 0.0, 1.0));
    case DistributionKind::lognormal:
      return x > 0.0 ? (std::log(x) - mu) / sigma : -kInf;
    case DistributionKind::discrete:
      return kNaN;
  }
  return kNaN;
}

double Distribution::calc_log_density(double x) const {
  constexpr double kHalfLog2Pi = 0.91893853320467274178;  // ln sqrt(2 pi)
  switch (kind) {
    case DistributionKind::normal: {
      const double t = (x - mean) / std;
      return -0.5 * t * t - std::log(std) - kHalfLog2Pi;
    }
    case DistributionKind::truncated_normal: {
      if (!(x >= lower && x <= upper)) return -kInf;
      const double t = (x - mean) / std;
      return -0.5 * t * t - std::log(std) - kHalfLog2Pi -
             std::log(truncated_mass((lower - mean) / std, (upper - mean) / std));
    }
    case DistributionKind::uniform:
      return x >= lower && x <= upper ? -std::log(upper - lower) : -kInf;
    case DistributionKind::lognormal: {
      if (!(x > 0.0)) return -kInf;
      const double t = (std::log(x) - mu) / sigma;
      return -0.5 * t * t - std::log(sigma) - std::log(x) - kHalfLog2Pi;
    }
    case DistributionKind::discrete:
      return kNaN;
  }
  return kNaN;
}

void Distribution::calc_quantiles(const double* u, double* x, std::size_t count) const {
  switch (kind) {
    case DistributionKind::normal:
      normal_quantiles(u, x, count);
      for (std::size_t i = 0; i < count; ++i) x[i] = mean + std * x[i];
      return;
    case DistributionKind::lognormal:
      normal_quantiles(u, x, count);
      for (std::size_t i = 0; i < count; ++i) x[i] = std::exp(mu + sigma * x[i]);
      return;
    default:
      for (std::size_t i = 0; i < count; ++i) x[i] = calc_quantile(u[i]);
      return;
  }
}

}  // namespace truss::sampling
