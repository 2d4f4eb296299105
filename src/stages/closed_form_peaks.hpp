// Peaks of a closed-form phase from samples that carry exact time derivatives (the velocity
// mode's held phases, phase_kinematic.hpp). For each tracked quantity Q (peaks.hpp):
//   - every sample is a candidate (a maximum at a phase end, at a kink, or at a grid point);
//   - between two samples of a smooth piece the cubic Hermite interpolant of (Q, Q') shows an
//     interior maximum where Q' changes sign from + to -, or where both end slopes have one sign
//     and the cubic still turns (a maximum hidden between two samples; confirmed by one probe);
//   - an interior maximum is the root of Q', bracketed by the samples and found by a secant step
//     safeguarded by regula falsi and bisection, to a few ulp of t: its time is exact to the
//     rounding of Q', not to the square root of the rounding of Q (a search on values).
// Spans are refined in the order of their Hermite estimate while that exceeds the best value
// found, and only for quantities whose best can change a record (PeakTracker::could_improve).
// Ties keep the earliest sample (docs/model.md §5).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "stages/peaks.hpp"

namespace truss::stages {

struct RatedSample {
  double t = 0;
  std::array<double, kQuantityCount> q{}, dq{};  // peak quantities and their time derivatives
  bool kink_before = false;                     // a smooth piece starts here: the span before it is not searched
};

// Interior maximum of the cubic Hermite interpolant on [a, b] of quantity k: at the fraction
// s in (0, 1), the interpolant's value there, and its other critical point (NaN if none in
// (0, 1)). found = false when the cubic has no maximum inside.
struct HermiteMaximum {
  bool found = false;
  double s = 0, value = 0, s_other = 0;
};
HermiteMaximum find_hermite_maximum(const RatedSample& a, const RatedSample& b, int k);

// How a quantity's peak is found: not at all (the model does not have it), as the best sample
// (a prescribed quantity, whose samples differ by rounding only), or with the interior maxima.
enum class PeakSearch { none, samples, full };

// Finds each quantity's peak over the samples (in time order) and offers it to the tracker's
// records with the tracker's bay. eval(t) -> RatedSample: one closed-form evaluation at t.
template <class Eval>
void absorb_rated_peaks(const std::vector<RatedSample>& samples, PeakTracker& tracker, Eval&& eval,
                        const std::array<PeakSearch, kQuantityCount>& search);

// --- implementation ---------------------------------------------------------------------------

namespace detail {

// Root of Q' (quantity k) in [lo, hi] with Q'(lo) >= 0 >= Q'(hi), starting at t: the time of the
// maximum and Q there in `out` (the last evaluated sample; its time moved to the root when the
// last secant step changes Q by less than its rounding: Q is flat there, t is not).
template <class Eval>
void refine_rated_root(int k, double lo, double glo, double hi, double ghi, double t, double t_prev, double g_prev,
                       Eval& eval, RatedSample& out) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const std::size_t ki = static_cast<std::size_t>(k);
  for (int it = 0; it < 60; ++it) {
    out = eval(t);
    const double g = out.dq[ki];
    if (g == 0.0 || !std::isfinite(g)) return;
    if (g > 0.0) { lo = t; glo = g; } else { hi = t; ghi = g; }
    const double tol = 4.0 * eps * std::max(1.0, std::abs(t));
    if (hi - lo <= tol) return;
    double tn = g != g_prev ? t - g * (t - t_prev) / (g - g_prev) : kNaN;  // secant
    if (std::abs(tn - t) <= tol) return;                                     // below the resolution of t
    if (tn > lo && tn < hi && std::abs(g * (tn - t)) <= eps * std::abs(out.q[ki])) {
      out.t = tn;  // Q(tn) = Q(t) + g (tn - t) / 2 + O(dt^2): the same to rounding
      return;
    }
    if (!(tn > lo && tn < hi)) tn = lo - glo * (hi - lo) / (ghi - glo);       // regula falsi
    if (!(tn > lo && tn < hi)) tn = 0.5 * (lo + hi);                           // bisection
    t_prev = t;
    g_prev = g;
    t = tn;
  }
}

}  // namespace detail

template <class Eval>
void absorb_rated_peaks(const std::vector<RatedSample>& samples, PeakTracker& tracker, Eval&& eval,
                        const std::array<PeakSearch, kQuantityCount>& search) {
  const std::size_t n = samples.size();
  for (int k = 0; k < kQuantityCount; ++k) {
    const std::size_t ki = static_cast<std::size_t>(k);
    if (search[ki] == PeakSearch::none) continue;
    double best = -kInf, best_t = kNaN;
    for (const RatedSample& s : samples)
      if (s.q[ki] > best) { best = s.q[ki]; best_t = s.t; }
    // Interior maxima of the smooth spans, by their Hermite estimate; a span is skipped when even
    // the bound of its cubic (within (|m0| + |m1|) 4/27 of its chord) cannot beat the record.
    const Extremum& record = tracker.target(k);
    const double floor = std::isfinite(record.value) ? std::max(best, record.value) : best;
    struct Span { std::size_t j; HermiteMaximum h; };
    thread_local std::vector<Span> spans;  // work space: no allocation per phase
    spans.clear();
    double top = best;
    for (std::size_t j = 0; j + 1 < n && search[ki] == PeakSearch::full; ++j) {
      const RatedSample& a = samples[j];
      const RatedSample& b = samples[j + 1];
      if (b.kink_before) continue;
      const double reach = 0.15 * (b.t - a.t) * (std::abs(a.dq[ki]) + std::abs(b.dq[ki]));
      if (!(std::max(a.q[ki], b.q[ki]) + reach > floor)) continue;
      const HermiteMaximum h = find_hermite_maximum(a, b, k);
      if (!h.found || !(h.value > best)) continue;
      spans.push_back({j, h});
      top = std::max(top, h.value);
    }
    if (!tracker.could_improve(k, top)) continue;
    std::stable_sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.h.value > b.h.value; });
    for (const Span& sp : spans) {
      if (!(sp.h.value > best)) break;
      const RatedSample& a = samples[sp.j];
      const RatedSample& b = samples[sp.j + 1];
      double lo = a.t, glo = a.dq[ki], hi = b.t, ghi = b.dq[ki];
      const double t_est = a.t + sp.h.s * (b.t - a.t);
      if (!(glo > 0.0 && ghi < 0.0)) {
        // A maximum hidden between two slopes of one sign: a probe between it and the cubic's
        // other critical point must show the slope's other sign to bracket it; else the span
        // holds no maximum above its samples.
        if (!std::isfinite(sp.h.s_other)) continue;
        const double t_probe = a.t + 0.5 * (sp.h.s + sp.h.s_other) * (b.t - a.t);
        const RatedSample p = eval(t_probe);
        if (p.q[ki] > best) { best = p.q[ki]; best_t = p.t; }
        const double g = p.dq[ki];
        if (glo <= 0.0 && g > 0.0) { lo = t_probe; glo = g; }
        else if (glo > 0.0 && g < 0.0) { hi = t_probe; ghi = g; }
        else continue;
      }
      RatedSample root;
      const bool near_lo = t_est - lo <= hi - t_est;  // the secant's first partner: the nearer end
      detail::refine_rated_root(k, lo, glo, hi, ghi, std::clamp(t_est, lo, hi), near_lo ? lo : hi,
                                near_lo ? glo : ghi, eval, root);
      if (root.q[ki] > best || (root.q[ki] == best && root.t < best_t)) { best = root.q[ki]; best_t = root.t; }
    }
    tracker.target(k).offer(best, best_t, tracker.bay);
  }
}

}  // namespace truss::stages
