// Peaks of a closed-form phase from samples that carry exact time derivatives (the velocity
// mode's held phases, phase_kinematic.hpp). For each tracked quantity Q (peaks.hpp):
//   - a sample is a local maximum at a phase end or a kink when its one-sided slopes say so;
//   - between two samples of a smooth piece the cubic Hermite interpolant of (Q, Q') shows an
//     interior maximum where Q' changes sign from + to -, or where both end slopes have one sign
//     and the cubic still turns (a maximum hidden between two samples; confirmed by one probe);
//   - an interior maximum is the root of Q', bracketed by the samples and found by a secant step
//     safeguarded by regula falsi and bisection, to a few ulp of t: its time is exact to the
//     rounding of Q', not to the square root of the rounding of Q (a search on values).
// Only quantities whose best can change a record are searched (PeakTracker::could_improve), and
// only the interior maxima that could be the highest or equal it are refined. Peaks equal to the
// run's accuracy (the record's tie tolerance, peaks.hpp) are one: the earliest of the phase's
// equal maxima is offered before the highest, as PhasePeaks does for time stepping.
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

namespace detail {
// A local maximum of a quantity in a phase: at a sample (a phase end, a kink, a zero slope) or
// inside a span (its Hermite estimate until refined).
struct Hill {
  double t, value;
  std::size_t span;  // the span (j, j + 1) of an interior maximum; kNoSpan at a sample
  HermiteMaximum h;
  bool exact;
};
}  // namespace detail

// Work space of the closed-form peak search, owned by the run (HeldStack) and reused phase after
// phase: no allocation per phase, and no thread_local (in a shared object such as the Python
// module every use of one is a call to __tls_get_addr).
struct RatedPeakWork {
  std::vector<RatedSample> samples;  // the phase's samples, in time order
  std::vector<detail::Hill> hills;   // one quantity's candidate maxima
};

// Finds each quantity's peak over work.samples (in time order) and offers it to the tracker's
// records with the tracker's bay. eval(t) -> RatedSample: one closed-form evaluation at t.
template <class Eval>
void absorb_rated_peaks(RatedPeakWork& work, PeakTracker& tracker, Eval&& eval,
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

namespace detail {

inline constexpr std::size_t kNoSpan = ~std::size_t{0};

// Refines an interior hill to the root of Q' (exact = true), or drops it (exact = false, value
// -inf) when a probe shows the Hermite cubic's hidden maximum is not there.
template <class Eval>
void refine_hill(int k, const std::vector<RatedSample>& samples, Eval& eval, Hill& hill) {
  const std::size_t ki = static_cast<std::size_t>(k);
  const RatedSample& a = samples[hill.span];
  const RatedSample& b = samples[hill.span + 1];
  double lo = a.t, glo = a.dq[ki], hi = b.t, ghi = b.dq[ki];
  const double t_est = hill.t;
  hill.value = -kInf;
  if (!(glo > 0.0 && ghi < 0.0)) {
    // A maximum hidden between two slopes of one sign: a probe between it and the cubic's other
    // critical point must show the slope's other sign to bracket it.
    if (!std::isfinite(hill.h.s_other)) return;
    const double t_probe = a.t + 0.5 * (hill.h.s + hill.h.s_other) * (b.t - a.t);
    const double g = eval(t_probe).dq[ki];
    if (glo <= 0.0 && g > 0.0) { lo = t_probe; glo = g; }
    else if (glo > 0.0 && g < 0.0) { hi = t_probe; ghi = g; }
    else return;
  }
  RatedSample root;
  const bool near_lo = t_est - lo <= hi - t_est;  // the secant's first partner: the nearer end
  refine_rated_root(k, lo, glo, hi, ghi, std::clamp(t_est, lo, hi), near_lo ? lo : hi, near_lo ? glo : ghi, eval, root);
  hill.t = root.t;
  hill.value = root.q[ki];
  hill.exact = true;
}

}  // namespace detail

template <class Eval>
void absorb_rated_peaks(RatedPeakWork& work, PeakTracker& tracker, Eval&& eval,
                        const std::array<PeakSearch, kQuantityCount>& search) {
  using detail::Hill;
  const std::vector<RatedSample>& samples = work.samples;
  std::vector<Hill>& hills = work.hills;
  const std::size_t n = samples.size();
  for (int k = 0; k < kQuantityCount; ++k) {
    const std::size_t ki = static_cast<std::size_t>(k);
    if (search[ki] == PeakSearch::none || n == 0) continue;
    Extremum& record = tracker.target(k);
    const double tol = record.tie_tol;  // equal peaks (to the run's accuracy, peaks.hpp) are one
    double best = -kInf;
    for (const RatedSample& s : samples) best = std::max(best, s.q[ki]);
    const double keep = best - tol * std::abs(best);  // below it no hill equals the phase's highest
    // Spans whose cubic cannot reach the record (nor equal it) are not searched.
    const double big = record.largest();
    const double floor = std::isfinite(record.value) ? std::max(keep, big - tol * std::abs(big)) : keep;
    hills.clear();
    double bound = best;  // no value of the phase above it
    for (std::size_t j = 0; j < n; ++j) {
      const RatedSample& s = samples[j];
      // At a sample: the phase start falling, the phase end rising, a kink rising into it and
      // falling out (its two samples share the value: the first counts), or a zero slope above both
      // neighbours.
      const bool starts = j == 0 || s.kink_before, ends = j + 1 == n || samples[j + 1].kink_before;
      bool hill;
      if (j + 1 < n && samples[j + 1].kink_before) hill = s.dq[ki] >= 0.0 && samples[j + 1].dq[ki] <= 0.0;
      else if (s.kink_before) hill = false;
      else if (starts || ends) hill = (!starts || s.dq[ki] <= 0.0) && (!ends || s.dq[ki] >= 0.0);
      else hill = s.dq[ki] == 0.0 && s.q[ki] >= samples[j - 1].q[ki] && s.q[ki] >= samples[j + 1].q[ki];
      if (hill && s.q[ki] >= keep) hills.push_back({s.t, s.q[ki], detail::kNoSpan, {}, true});
      if (ends || search[ki] != PeakSearch::full) continue;
      const RatedSample& b = samples[j + 1];
      // The bound of the span's cubic (within (|m0| + |m1|) 4/27 of its chord) must reach the floor.
      const double chord = std::max(s.q[ki], b.q[ki]);
      if (!(chord + 0.15 * (b.t - s.t) * (std::abs(s.dq[ki]) + std::abs(b.dq[ki])) >= floor)) continue;
      const HermiteMaximum h = find_hermite_maximum(s, b, k);
      if (!h.found || !(h.value >= keep)) continue;
      hills.push_back({s.t + h.s * (b.t - s.t), h.value, j, h, false});
      bound = std::max(bound, 2.0 * h.value - chord);  // the estimate's rise above the chord, twice
    }
    // Slopes at the rounding level can leave no sample a hill (a prescribed quantity): then the
    // highest sample is the peak.
    if (hills.empty()) {
      std::size_t jb = 0;
      for (std::size_t j = 1; j < n; ++j)
        if (samples[j].q[ki] > samples[jb].q[ki]) jb = j;
      hills.push_back({samples[jb].t, samples[jb].q[ki], detail::kNoSpan, {}, true});
    }
    if (!tracker.could_improve(k, bound)) continue;
    // Refine the interior hills, highest estimate first, while one could still be the highest or
    // equal it (its estimate's rise above the chord taken twice).
    for (;;) {
      double top = -kInf;
      Hill* next = nullptr;
      for (Hill& h : hills) {
        if (h.exact) top = std::max(top, h.value);
        else if (!next || h.value > next->value) next = &h;
      }
      if (!next) break;
      const RatedSample& a = samples[next->span];
      const double chord = std::max(a.q[ki], samples[next->span + 1].q[ki]);
      if (std::isfinite(top) && 2.0 * next->value - chord < top - tol * std::abs(top)) break;
      detail::refine_hill(k, samples, eval, *next);
      next->exact = true;  // refined, or dropped with value -inf
    }
    const Hill* top = nullptr;
    for (const Hill& h : hills)
      if (h.exact && h.value > -kInf && (!top || h.value > top->value)) top = &h;
    if (!top) continue;
    // Hills are in time order but for the interior ones refined past a sample: the earliest equal.
    const Hill* first = top;
    for (const Hill& h : hills)
      if (h.exact && h.value > -kInf && h.t < first->t && is_tie(h.value, top->value, tol)) first = &h;
    if (first != top) record.offer(first->value, first->t, tracker.bay);
    record.offer(top->value, top->t, tracker.bay);
  }
}

}  // namespace truss::stages
