// reweighting.cpp — likelihood ratios between draw laws and the weighted estimate (reweighting.hpp).
#include "sampling/reweighting.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

namespace truss::sampling {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Support {
  double lo = -kInf, hi = kInf;
};

// The support of X's law (closed where it has an end), mapped by the draw's affine map.
Support find_support(const DrawLaw& law) {
  Support s;
  const Distribution& d = law.dist;
  if (d.kind == DistributionKind::truncated_normal || d.kind == DistributionKind::uniform) {
    s.lo = d.lower;
    s.hi = d.upper;
  } else if (d.kind == DistributionKind::lognormal) {
    s.lo = 0.0;
  }
  return {law.scale * s.lo + law.shift, law.scale * s.hi + law.shift};
}

}  // namespace

double calc_pareto_k(std::vector<double> w) {
  const std::size_t s = w.size();
  if (s < 5) return std::numeric_limits<double>::quiet_NaN();
  const auto m = static_cast<std::size_t>(
      std::min(std::ceil(0.2 * static_cast<double>(s)), std::ceil(3.0 * std::sqrt(static_cast<double>(s)))));
  std::sort(w.begin(), w.end());
  const double cut = w[s - m - 1];
  std::vector<double> x(m);  // the exceedances, ascending
  for (std::size_t i = 0; i < m; ++i) x[i] = w[s - m + i] - cut;
  if (!(x.back() > 0.0)) return -kInf;  // the largest weights are equal: no tail at all
  // Zhang & Stephens: a grid of b = 1 / x_max + (1 - sqrt(g / (i - 1/2))) / (3 x_quartile), each with
  // its profile likelihood; the posterior mean of b, then k.
  const double n = static_cast<double>(m);
  const auto g = static_cast<std::size_t>(30 + std::floor(std::sqrt(n)));
  const double quartile = x[static_cast<std::size_t>(std::floor(n / 4.0 + 0.5)) - 1];
  std::vector<double> b(g), len(g);
  for (std::size_t i = 0; i < g; ++i) {
    b[i] = 1.0 / x.back() + (1.0 - std::sqrt(static_cast<double>(g) / (static_cast<double>(i) + 0.5))) /
                                (3.0 * quartile);
    double k = 0.0;
    for (double v : x) k += std::log1p(-b[i] * v);
    k /= n;
    len[i] = n * (std::log(-b[i] / k) - k - 1.0);
  }
  double b_post = 0.0, total = 0.0;
  for (std::size_t i = 0; i < g; ++i) {
    double sum = 0.0;  // 1 / weight_i = sum_j exp(len_j - len_i)
    for (std::size_t j = 0; j < g; ++j) sum += std::exp(len[j] - len[i]);
    const double weight = 1.0 / sum;
    b_post += b[i] * weight;
    total += weight;
  }
  b_post /= total;
  double k = 0.0;
  for (double v : x) k += std::log1p(-b_post * v);
  k /= n;
  return (n * k + 10.0 * 0.5) / (n + 10.0);  // the weakly informative prior of Vehtari et al.
}

double DrawLaw::calc_log_density(double d) const {
  return dist.calc_log_density((d - shift) / scale) - std::log(scale);
}

std::string DrawLaw::validate() const {
  if (const std::string why = dist.validate(); !why.empty()) return why;
  if (!(scale > 0.0) || !std::isfinite(scale)) return fmt::format("scale: must be > 0 and finite (got {})", scale);
  if (!std::isfinite(shift)) return fmt::format("shift: must be finite (got {})", shift);
  return "";
}

std::string find_reweighting_refusal(const DrawLaw& base, const DrawLaw& target) {
  if (const std::string why = base.validate(); !why.empty()) return "the sampled law: " + why;
  if (const std::string why = target.validate(); !why.empty()) return "the target law: " + why;
  if (base.dist.kind == DistributionKind::discrete || target.dist.kind == DistributionKind::discrete)
    return "a discrete law has no density: its runs serve only their own law";
  const Support b = find_support(base), t = find_support(target);
  if (t.lo < b.lo || t.hi > b.hi)
    return fmt::format("the target's draws reach [{:.6g}, {:.6g}], beyond the sampled law's [{:.6g}, {:.6g}]: the "
                       "runs never see that part", t.lo, t.hi, b.lo, b.hi);
  return "";
}

WeightedEstimate calc_weighted_estimate(std::span<const double> margins, std::span<const double> log_w,
                                        double confidence) {
  if (margins.size() != log_w.size()) throw std::invalid_argument("calc_weighted_estimate: one weight per run");
  WeightedEstimate e;
  e.runs = static_cast<std::int64_t>(margins.size());
  // The failing runs' weights, scaled by the largest (exp of ln w - max: no overflow).
  double top = -kInf;
  for (std::size_t i = 0; i < margins.size(); ++i) {
    e.unusable += std::isnan(margins[i]) ? 1 : 0;
    if (margins[i] <= 0.0) {
      ++e.failures;
      top = std::max(top, log_w[i]);
    }
  }
  if (e.runs == 0 || e.failures == 0) {
    e.p = 0.0;
    e.refused = fmt::format("no failing run among {}", e.runs);
    return e;
  }
  if (!std::isfinite(top)) {
    e.p = top == -kInf ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    e.refused = fmt::format("the {} failing runs have no finite weight under this law", e.failures);
    return e;
  }
  double s1 = 0.0, s2 = 0.0;  // sum w / W, sum (w / W)^2 over failing runs, W = exp(top)
  for (std::size_t i = 0; i < margins.size(); ++i) {
    if (!(margins[i] <= 0.0)) continue;
    const double w = std::exp(log_w[i] - top);
    s1 += w;
    s2 += w * w;
  }
  const double n = static_cast<double>(e.runs), scale = std::exp(top);
  e.p = scale * s1 / n;
  e.ess = s1 * s1 / s2;
  // Sample variance of y_i = 1{fail} w_i: (sum y^2 - n p^2) / (n - 1), in units of W^2.
  const double mean = s1 / n, var = e.runs > 1 ? std::max(0.0, (s2 - n * mean * mean) / (n - 1.0)) : kInf;
  e.cov = std::sqrt(var / n) / mean;
  std::vector<double> failing;
  for (std::size_t i = 0; i < margins.size(); ++i)
    if (margins[i] <= 0.0) failing.push_back(std::exp(log_w[i] - top));
  e.pareto_k = calc_pareto_k(std::move(failing));
  if (e.ess < kMinEss) {
    e.refused = fmt::format("the weights of the {} failing runs degenerate: an effective sample size of {:.3g} "
                            "(at least {:g} needed)", e.failures, e.ess, kMinEss);
    return e;
  }
  if (!(e.pareto_k <= kMaxParetoK)) {
    e.refused = fmt::format("the weights of the {} failing runs have a heavy tail: Pareto k = {:.3g} (at most {:g}; "
                            "the sample variance does not hold)", e.failures, e.pareto_k, kMaxParetoK);
    return e;
  }
  e.bounds = calc_lognormal_bounds(e.p, e.cov, confidence);
  return e;
}

}  // namespace truss::sampling
