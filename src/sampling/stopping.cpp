// stopping.cpp — sequential stopping rules; definitions and sources in stopping.hpp.
#include "sampling/stopping.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <boost/math/distributions/binomial.hpp>
#include <fmt/format.h>

namespace truss::sampling {

namespace {

using Binomial = boost::math::binomial_distribution<double>;

// The narrowest Clopper-Pearson half-width n trials can give: at k = 0 the interval is
// [0, 1 - a^(1/n)] (and at k = n its mirror image), a = (1 - confidence) / 2.
double calc_narrowest_half_width(std::int64_t n, double confidence) {
  const double a = 0.5 * (1.0 - confidence);
  return 0.5 * -std::expm1(std::log(a) / static_cast<double>(n));
}

// The next round's runs for a width that shrinks as n^-1/2: n (achieved / target)^2, between
// 1.25 n and 4 n, never past the cap.
std::int64_t calc_next_runs(std::int64_t n, double achieved, double target, std::int64_t max_runs) {
  const double dn = static_cast<double>(n);
  double total = std::isfinite(achieved) ? dn * (achieved / target) * (achieved / target) : 4.0 * dn;
  total = std::clamp(total, 1.25 * dn, 4.0 * dn);
  const auto next = std::min(static_cast<std::int64_t>(std::ceil(total)), max_runs);
  return std::max<std::int64_t>(next - n, 0);
}

// met / capped / more, from whether the target holds and the runs so far.
void settle(StopDecision& d, const StopRule& rule, bool met, std::int64_t wanted) {
  if (met) {
    d.state = StopState::met;
  } else if (d.runs >= rule.max_runs) {
    d.state = StopState::capped;
    d.reason += fmt::format("; max_runs = {} reached", rule.max_runs);
  } else {
    d.state = StopState::more;
    d.next_runs = std::min(wanted, rule.max_runs - d.runs);
  }
}

}  // namespace

Interval calc_clopper_pearson(std::int64_t k, std::int64_t n, double confidence) {
  if (n < 1 || k < 0 || k > n || !(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument(fmt::format("Clopper-Pearson interval of {} in {} at confidence {}", k, n, confidence));
  const double a = 0.5 * (1.0 - confidence);
  const auto dn = static_cast<double>(n), dk = static_cast<double>(k);
  return {Binomial::find_lower_bound_on_p(dn, dk, a), Binomial::find_upper_bound_on_p(dn, dk, a)};
}

std::int64_t calc_upper_bound_rank(std::int64_t n, double q, double confidence) {
  if (n < 1) return 0;
  const Binomial b(static_cast<double>(n), q);
  const auto cdf = [&](std::int64_t k) { return boost::math::cdf(b, static_cast<double>(k - 1)); };  // F(k - 1)
  if (cdf(n) < confidence) return 0;
  std::int64_t lo = 1, hi = n;  // cdf(hi) >= confidence; find the least such rank
  while (lo < hi) {
    const std::int64_t mid = lo + (hi - lo) / 2;
    if (cdf(mid) >= confidence) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

std::int64_t calc_runs_for_upper_bound(double q, double confidence) {
  // 1 - q^n >= confidence  <=>  n log q <= log(1 - confidence); the float estimate, then exact steps.
  auto n = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::floor(std::log1p(-confidence) / std::log(q))));
  const auto has = [&](std::int64_t m) { return -std::expm1(static_cast<double>(m) * std::log(q)) >= confidence; };
  while (!has(n)) ++n;
  while (n > 1 && has(n - 1)) --n;
  return n;
}

double calc_percentile_sorted(std::span<const double> sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double h = static_cast<double>(sorted.size() - 1) * q;
  const auto i = static_cast<std::size_t>(std::floor(h));
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (h - static_cast<double>(i)) * (sorted[i + 1] - sorted[i]);
}

std::string StopRule::validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) return fmt::format("confidence: {} (must lie in (0, 1))", confidence);
  if (!(width > 0.0 && std::isfinite(width))) return fmt::format("width: {} (must be positive and finite)", width);
  if (max_runs < 1) return fmt::format("max_runs: {} (at least 1)", max_runs);
  // Run counts stay exact in doubles (the next round's size is computed in them, up to 4 times the
  // runs so far).
  if (max_runs > (std::int64_t{1} << 53)) return fmt::format("max_runs: {} (at most 2^53 runs)", max_runs);
  if (target == StopTarget::percentile_bound) {
    if (!(level > 0.0 && level < 1.0)) return fmt::format("level: {} (a quantile level in (0, 1))", level);
    const std::int64_t need = calc_runs_for_upper_bound(level, confidence);
    if (need > max_runs)
      return fmt::format("max_runs: {} runs can never give a one-sided bound of the {} quantile at confidence {} "
                         "(that needs at least {} runs)", max_runs, level, confidence, need);
    return "";
  }
  const double narrowest = calc_narrowest_half_width(max_runs, confidence);
  if (width < narrowest)
    return fmt::format("width: {} is below the narrowest {}half-width that max_runs = {} runs can give at "
                       "confidence {} ({:.3g})", width,
                       target == StopTarget::probability_relative_half_width ? "relative " : "", max_runs,
                       confidence, narrowest);
  return "";
}

StopDecision decide_probability_stop(const StopRule& rule, std::int64_t failures, std::int64_t runs) {
  StopDecision d;
  d.runs = d.used = runs;
  if (runs < 1) {
    d.reason = "no runs yet";
    settle(d, rule, false, std::min<std::int64_t>(rule.max_runs, 100));
    return d;
  }
  const Interval ci = calc_clopper_pearson(failures, runs, rule.confidence);
  d.estimate = static_cast<double>(failures) / static_cast<double>(runs);
  d.lo = ci.lo;
  d.hi = ci.hi;
  const bool relative = rule.target == StopTarget::probability_relative_half_width;
  d.achieved = relative ? (failures > 0 ? ci.half_width() / d.estimate : std::numeric_limits<double>::infinity())
                        : ci.half_width();
  const bool met = d.achieved <= rule.width;
  d.reason = fmt::format("{} failures in {} runs: p = {:.4g}, {:.4g} % interval [{:.4g}, {:.4g}], {}half-width {:.4g} "
                         "{} {:.4g}", failures, runs, d.estimate, 100.0 * rule.confidence, ci.lo, ci.hi,
                         relative ? "relative " : "", d.achieved, met ? "<=" : ">", rule.width);
  settle(d, rule, met, calc_next_runs(runs, d.achieved, rule.width, rule.max_runs));
  return d;
}

StopDecision decide_percentile_stop(const StopRule& rule, std::span<const double> values) {
  StopDecision d;
  d.runs = static_cast<std::int64_t>(values.size());
  std::vector<double> v;
  v.reserve(values.size());
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  std::sort(v.begin(), v.end());
  d.used = static_cast<std::int64_t>(v.size());
  d.estimate = calc_percentile_sorted(v, rule.level);
  d.bound_rank = calc_upper_bound_rank(d.used, rule.level, rule.confidence);
  if (d.bound_rank == 0) {
    const std::int64_t need = calc_runs_for_upper_bound(rule.level, rule.confidence);
    d.reason = fmt::format("{} usable values: a one-sided bound of the {} quantile at confidence {} needs {}",
                           d.used, rule.level, rule.confidence, need);
    // Runs without a value are expected again in the same proportion.
    const double per_value = d.used > 0 ? static_cast<double>(d.runs) / static_cast<double>(d.used) : 1.0;
    settle(d, rule, false, static_cast<std::int64_t>(std::ceil(static_cast<double>(need - d.used) * per_value)));
    return d;
  }
  d.hi = v[static_cast<std::size_t>(d.bound_rank - 1)];
  const double excess = d.hi - d.estimate;
  d.achieved = excess == 0.0 ? 0.0 : excess / std::abs(d.estimate);  // estimate 0 with a larger bound: inf
  const bool met = d.achieved <= rule.width;
  d.reason = fmt::format("{} usable values: the {} quantile {:.6g}, its upper bound x_({}) = {:.6g} at confidence {}, "
                         "relative width {:.4g} {} {:.4g}", d.used, rule.level, d.estimate, d.bound_rank, d.hi,
                         rule.confidence, d.achieved, met ? "<=" : ">", rule.width);
  settle(d, rule, met, calc_next_runs(d.runs, d.achieved, rule.width, rule.max_runs));
  return d;
}

}  // namespace truss::sampling
