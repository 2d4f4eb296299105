// monotone_fit.cpp — the isotonic fit of a sweep's estimates and its allowable; the method and its
// sources are stated in monotone_fit.hpp.
#include "sampling/monotone_fit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::sampling {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A value's point on the log scale and its weight: ln p^ and 1 / var (lognormal); the
// continuity-corrected ln k / n and its delta-method weight (binomial, for the trend only).
struct LogPoint {
  double y = kNaN, w = 0.0;
};

LogPoint calc_log_point(const SweepEstimate& e) {
  if (e.kind == EstimateKind::lognormal) return {std::log(e.p), 1.0 / std::log1p(e.cov * e.cov)};
  const double k = static_cast<double>(e.failures) + 0.5, n = static_cast<double>(e.runs) + 0.5;
  return {std::log(k / n), 1.0 / (1.0 / k - 1.0 / n)};
}

// Why a value cannot enter the fit ("" when it can).
std::string find_exclusion(const SweepEstimate& e) {
  if (!e.untrusted.empty()) return e.untrusted;
  if (e.kind == EstimateKind::binomial)
    return e.runs > 0 && e.failures >= 0 && e.failures <= e.runs ? "" : "no runs";
  return e.p > 0.0 && std::isfinite(e.p) && e.cov > 0.0 && std::isfinite(e.cov) ? "" : "no estimate with a CoV";
}

// A block of the pool-adjacent-violators algorithm: consecutive values (in order from the safe end).
struct Block {
  double sw = 0.0, swy = 0.0;            // lognormal: sum w, sum w ln p^
  std::int64_t failures = 0, runs = 0;  // binomial
  std::size_t first = 0, last = 0;      // positions in the order from the safe end
  double calc_level(EstimateKind kind) const {
    return kind == EstimateKind::lognormal ? swy / sw : static_cast<double>(failures) / static_cast<double>(runs);
  }
  void merge(const Block& b) {
    sw += b.sw;
    swy += b.swy;
    failures += b.failures;
    runs += b.runs;
    last = b.last;
  }
};

// Weighted pool-adjacent-violators: the blocks of `order` (indices, safest first) whose levels do
// not decrease away from the safe end.
std::vector<Block> calc_blocks(const std::vector<SweepEstimate>& v, const std::vector<std::size_t>& order) {
  const EstimateKind kind = v[order.front()].kind;
  std::vector<Block> blocks;
  for (std::size_t pos = 0; pos < order.size(); ++pos) {
    const SweepEstimate& e = v[order[pos]];
    Block b;
    if (kind == EstimateKind::lognormal) {
      const LogPoint lp = calc_log_point(e);
      b.sw = lp.w;
      b.swy = lp.w * lp.y;
    }
    b.failures = e.failures;
    b.runs = e.runs;
    b.first = b.last = pos;
    blocks.push_back(b);
    while (blocks.size() > 1 && blocks[blocks.size() - 2].calc_level(kind) > blocks.back().calc_level(kind)) {
      const Block top = blocks.back();
      blocks.pop_back();
      blocks.back().merge(top);
    }
  }
  return blocks;
}

// A value's fitted bounds: its block's estimate with the value's own precision (see the header).
ProbabilityBounds calc_fitted_bounds(const Block& b, const SweepEstimate& e, double confidence) {
  if (e.kind == EstimateKind::lognormal) {
    return calc_lognormal_bounds(std::exp(b.swy / b.sw), e.cov, confidence);
  }
  const double rate = b.calc_level(EstimateKind::binomial);
  const auto k = static_cast<std::int64_t>(std::ceil(rate * static_cast<double>(e.runs) - 1e-9));
  ProbabilityBounds r = calc_binomial_bounds(std::min(k, e.runs), e.runs, confidence);
  r.p = rate;
  return r;
}

// The weighted least-squares slope of the log points against x, in standard errors, signed positive
// when p falls towards the safe side.
double calc_trend_z(const std::vector<SweepEstimate>& v, const std::vector<std::size_t>& fitted, int safe_side) {
  double sw = 0.0, swx = 0.0, swy = 0.0;
  for (std::size_t i : fitted) {
    const LogPoint lp = calc_log_point(v[i]);
    sw += lp.w;
    swx += lp.w * v[i].x;
    swy += lp.w * lp.y;
  }
  const double mx = swx / sw, my = swy / sw;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t i : fitted) {
    const LogPoint lp = calc_log_point(v[i]);
    sxx += lp.w * (v[i].x - mx) * (v[i].x - mx);
    sxy += lp.w * (v[i].x - mx) * (lp.y - my);
  }
  return -static_cast<double>(safe_side) * (sxy / sxx) * std::sqrt(sxx);
}

std::string join_values(const std::vector<SweepEstimate>& v, const std::vector<std::size_t>& idx,
                        const std::string& unit) {
  std::string t;
  for (std::size_t k = 0; k < idx.size(); ++k)
    t += fmt::format("{}{:g}{}", k == 0 ? "" : k + 1 == idx.size() ? " and " : ", ", v[idx[k]].x, unit);
  return t;
}

// The sentence on excluded and pooled values that ends the allowable's message.
std::string calc_fit_note(const std::vector<SweepEstimate>& v, const MonotoneFit& f, const std::vector<Block>& blocks,
                          const std::vector<std::size_t>& order, const std::string& unit) {
  std::string note;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!f.excluded[i].empty()) note += fmt::format("; {:g}{} not used: {}", v[i].x, unit, f.excluded[i]);
  for (const Block& b : blocks) {
    if (b.first == b.last) continue;
    std::vector<std::size_t> idx(order.begin() + static_cast<std::ptrdiff_t>(b.first),
                                 order.begin() + static_cast<std::ptrdiff_t>(b.last + 1));
    std::sort(idx.begin(), idx.end());
    note += fmt::format("; {} pooled (their estimates do not fall towards the safe side)", join_values(v, idx, unit));
  }
  return note.empty() ? note : " (" + note.substr(2) + ")";
}

}  // namespace

MonotoneFit calc_monotone_fit(const std::vector<SweepEstimate>& v, int safe_side, double target, double confidence,
                              const std::string& units) {
  if (safe_side != 1 && safe_side != -1) throw std::invalid_argument("calc_monotone_fit: safe side +1 or -1");
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0 && !(v[i].x > v[i - 1].x)) throw std::invalid_argument("calc_monotone_fit: values not ascending");
    if (v[i].kind != v.front().kind) throw std::invalid_argument("calc_monotone_fit: estimates of two kinds");
  }
  const std::string unit = units.empty() ? std::string() : " " + units;
  MonotoneFit f;
  f.fitted.assign(v.size(), ProbabilityBounds{});
  f.block.assign(v.size(), -1);
  f.excluded.resize(v.size());
  std::vector<std::size_t> order;  // the fitted values, safest first
  for (std::size_t i = 0; i < v.size(); ++i) {
    f.excluded[i] = find_exclusion(v[i]);
    if (f.excluded[i].empty()) order.push_back(i);
  }
  if (safe_side > 0) std::reverse(order.begin(), order.end());
  f.allowable.safe_side = safe_side;
  if (order.size() < 2) {
    f.allowable.message = fmt::format("{} of {} values have an estimate that can be used: no allowable{}",
                                      order.size(), v.size(), calc_fit_note(v, f, {}, order, unit));
    return f;
  }
  const std::vector<Block> blocks = calc_blocks(v, order);
  for (std::size_t b = 0; b < blocks.size(); ++b)
    for (std::size_t pos = blocks[b].first; pos <= blocks[b].last; ++pos) {
      f.block[order[pos]] = static_cast<int>(b);
      f.fitted[order[pos]] = calc_fitted_bounds(blocks[b], v[order[pos]], confidence);
    }
  const std::string note = calc_fit_note(v, f, blocks, order, unit);
  f.trend_z = calc_trend_z(v, order, safe_side);
  if (f.trend_z < -kContradictingTrendZ) {
    f.allowable.status = AllowableStatus::contradicts_safe_side;
    f.allowable.message = fmt::format("the estimates rise towards the declared safe side ({}: the trend of ln p is "
                                      "{:.3g} standard errors the other way): the declared safe side or the failure "
                                      "event is wrong{}",
                                      safe_side > 0 ? "above" : "below", -f.trend_z, note);
    return f;
  }
  std::vector<double> x;
  for (const SweepEstimate& e : v) x.push_back(e.x);
  f.allowable = find_allowable_on_side(x, f.fitted, safe_side, target, units, note);
  return f;
}

}  // namespace truss::sampling
