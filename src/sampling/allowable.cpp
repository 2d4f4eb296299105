#include "sampling/allowable.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "sampling/sampling.hpp"
#include "sampling/stopping.hpp"

namespace truss::sampling {

ProbabilityBounds calc_lognormal_bounds(double p, double cov, double confidence) {
  ProbabilityBounds b;
  b.p = p;
  if (!(p > 0.0) || !std::isfinite(cov) || cov < 0.0) return b;
  const double s = std::sqrt(std::log1p(cov * cov));
  b.upper_bound = p * std::exp(normal_quantile(confidence) * s);
  const double z2 = normal_quantile(0.5 * (1.0 + confidence));
  b.lower = p * std::exp(-z2 * s);
  b.upper = p * std::exp(z2 * s);
  return b;
}

ProbabilityBounds calc_binomial_bounds(std::int64_t k, std::int64_t n, double confidence) {
  ProbabilityBounds b;
  if (n < 1) return b;
  b.p = static_cast<double>(k) / static_cast<double>(n);
  b.upper_bound = calc_clopper_pearson(k, n, 2.0 * confidence - 1.0).hi;
  const Interval two = calc_clopper_pearson(k, n, confidence);
  b.lower = two.lo;
  b.upper = two.hi;
  return b;
}

namespace {

// The crossing of curve y (over the usable values, in the order `from_safe`) with the target: the
// design value where it first exceeds the target, interpolated in ln y; NaN when it starts above
// the target (`starts_above`) or never exceeds it.
struct Crossing {
  double x = std::nan("");
  bool starts_above = false, never = false;
  int a = -1, b = -1;
};

Crossing cross(const std::vector<double>& x, const std::vector<double>& y, const std::vector<int>& from_safe,
               double target) {
  Crossing c;
  if (y[static_cast<std::size_t>(from_safe.front())] > target) {
    c.starts_above = true;
    return c;
  }
  for (std::size_t j = 1; j < from_safe.size(); ++j) {
    const auto a = static_cast<std::size_t>(from_safe[j - 1]), b = static_cast<std::size_t>(from_safe[j]);
    if (!(y[b] > target)) continue;
    c.a = from_safe[j - 1];
    c.b = from_safe[j];
    if (!(y[a] > 0.0)) {
      c.x = x[b];
      return c;
    }
    const double t = (std::log(target) - std::log(y[a])) / (std::log(y[b]) - std::log(y[a]));
    c.x = x[a] + (x[b] - x[a]) * t;
    return c;
  }
  c.never = true;
  return c;
}

std::vector<int> find_usable(const std::vector<ProbabilityBounds>& b) {
  std::vector<int> usable;
  for (std::size_t i = 0; i < b.size(); ++i)
    if (b[i].usable()) usable.push_back(static_cast<int>(i));
  return usable;
}

}  // namespace

Allowable find_allowable_on_side(const std::vector<double>& x, const std::vector<ProbabilityBounds>& b,
                                 int safe_side, double target, const std::string& units, const std::string& note) {
  if (x.size() != b.size()) throw std::invalid_argument("find_allowable_on_side: one bounds per value");
  if (safe_side != 1 && safe_side != -1) throw std::invalid_argument("find_allowable_on_side: safe side +1 or -1");
  Allowable r;
  const std::vector<int> usable = find_usable(b);
  r.safe_side = safe_side;
  if (usable.size() < 2) {
    r.message = fmt::format("{} of {} values have an estimate with bounds: no allowable", usable.size(), x.size());
    return r;
  }
  std::vector<double> ub(x.size()), p(x.size()), lo(x.size()), hi(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    ub[i] = b[i].upper_bound;
    p[i] = b[i].p;
    lo[i] = b[i].lower;
    hi[i] = b[i].upper;
  }
  const std::string unit = units.empty() ? std::string() : " " + units;
  std::vector<int> from_safe(usable.begin(), usable.end());
  if (r.safe_side > 0) std::reverse(from_safe.begin(), from_safe.end());
  // The ends named by their values: the safe and unsafe ends of the values that have an estimate.
  const double safe_x = x[static_cast<std::size_t>(from_safe.front())];
  const double unsafe_x = x[static_cast<std::size_t>(from_safe.back())];
  const char* extend_safe = r.safe_side > 0 ? "above" : "below";
  const char* extend_unsafe = r.safe_side > 0 ? "below" : "above";
  const std::string notes =
      note + (usable.size() < x.size()
                      ? fmt::format(" ({} of {} values have no estimate)", x.size() - usable.size(), x.size())
                      : std::string());
  const Crossing u = cross(x, ub, from_safe, target);
  const Crossing e = cross(x, p, from_safe, target);
  const Crossing band_hi = cross(x, hi, from_safe, target), band_lo = cross(x, lo, from_safe, target);
  // The interval: between the crossings of the interval's top (nearer the safe end) and bottom.
  const double near_safe = band_hi.x, near_unsafe = band_lo.x;
  r.lower = r.safe_side > 0 ? near_unsafe : near_safe;
  r.upper = r.safe_side > 0 ? near_safe : near_unsafe;
  r.estimate = e.x;
  if (u.starts_above) {
    r.status = AllowableStatus::beyond_safe_end;
    r.message = fmt::format("even the upper bound on p at {:g}{}, the safest value with an estimate, exceeds the "
                            "target: the allowable lies beyond it; extend the sweep {} {:g}{}{}",
                            safe_x, unit, extend_safe, safe_x, unit, notes);
    return r;
  }
  if (u.never) {
    r.status = AllowableStatus::beyond_unsafe_end;
    r.message = fmt::format("every value's upper bound on p is at or below the target: the allowable lies beyond "
                            "the swept range; extend it {} {:g}{}{}",
                            extend_unsafe, unsafe_x, unit, notes);
    return r;
  }
  r.status = AllowableStatus::found;
  r.value = u.x;
  r.bracket_safe = u.a;
  r.bracket_unsafe = u.b;
  r.message = fmt::format("the upper bound on p crosses the target between values {}{} and {}{}{}",
                          x[static_cast<std::size_t>(u.a)], unit, x[static_cast<std::size_t>(u.b)], unit, note);
  return r;
}

}  // namespace truss::sampling
