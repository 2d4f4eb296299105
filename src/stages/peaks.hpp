// Peak tracking (docs/model.md §5: peaks with their time and bay; the earliest where one repeats).
// "Repeats" is read to the run's accuracy: peaks within a relative tie tolerance of the largest
// (the run's allowed relative error, energy.hpp) are one peak, reported with the largest value at
// the time and bay where it first occurs (docs/model-notes.md, "Equal peaks").
// A phase's samples (step ends, or a grid in closed form) are fed in time order; for each tracked
// quantity PhasePeaks keeps its best sample and the two neighbours that bracket it, and refine()
// maximises between them, on the exact closed form or on a quintic Hermite interpolant of the
// state. PeakTracker keeps the records of the run and of the current stage. Neither knows the
// size or layout of a phase's state: a sample carries it as (q, q', q'') of any length.
#pragma once
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "numerics/brent.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Two values are one peak when they differ by at most tol of the larger's magnitude.
inline bool is_tie(double v, double larger, double tol) { return v >= larger - tol * std::abs(larger); }

// The largest of values offered in time order (value), at the time and bay of the earliest offer
// within the tie tolerance of it (t, bay).
struct Extremum {
  double value = -kInf;
  double t = kNaN;
  int bay = 0;
  double tie_tol = 0.0;  // relative
  // True if the reported offer changed.
  bool offer(double v, double time, int b) {
    if (!(v > -kInf) || (!ties_.empty() && !is_tie(v, max_, tie_tol))) return false;
    if (ties_.empty() || v > max_) {
      max_ = v;
      std::erase_if(ties_, [&](const Offer& o) { return !is_tie(o.v, max_, tie_tol); });
    }
    ties_.push_back({v, time, b});
    const Offer& first = ties_.front();
    const bool changed = max_ != value || !(first.t == t) || first.b != bay;
    value = max_; t = first.t; bay = first.b;
    return changed;
  }
  void clear() {
    value = max_ = -kInf;
    t = kNaN;
    bay = 0;
    ties_.clear();
  }
  double largest() const { return max_; }

 private:
  struct Offer { double v, t; int b; };
  double max_ = -kInf;
  std::vector<Offer> ties_;  // the offers within the tie tolerance of max_, in time order
};

// Quantities whose extremes a run reports. kRailApproach is minus the hinge's distance from the
// rail (free stack, open phase; -inf elsewhere): its maximum is the stage's closest approach.
// kOverlap is minus the smallest bay opening (free stack): its maximum is the deepest overlap.
// kStaticForce and kInertialForce are the spring (static) and the inertial part of the drive
// force along the run direction (PhasePoint::static_drive_force_N; NaN, never a record, where
// the static part is not defined).
enum PeakQuantity { kForce, kNegForce, kPin, kTension, kSpeed, kRailApproach, kOverlap, kStaticForce, kInertialForce,
                    kQuantityCount };
// In the point's number type (double, or a dual number: then with its time derivative).
template <class T>
T calc_peak_quantity(int q, const PhasePointT<T>& p, double direction) {
  switch (q) {
    case kForce: return p.drive_force_N;
    case kNegForce: return -p.drive_force_N;
    case kPin: return p.pin_force_N;
    case kTension: return p.diagonal_tension_N;
    case kRailApproach: return -p.rail_distance_m;
    case kOverlap: return -p.min_bay_opening_m;
    case kStaticForce: return direction * p.static_drive_force_N;
    case kInertialForce: return direction * (p.drive_force_N - p.static_drive_force_N);
    default: return direction * p.u_m_per_s;
  }
}

// The quantities that do not change during a phase of this kind, so that their best sample is their
// peak (PeakTracker::absorb searches nothing for them): off the rail the pin force, zero there
// (PhasePoint::pin_force_N). A bit set for each, 1 << quantity.
inline unsigned find_constant_quantities(PhaseKind kind) { return kind == PhaseKind::open ? 1u << kPin : 0u; }

struct Sample {
  double t = 0;
  PhasePoint p;
  std::vector<double> state;  // (q, q', q'') of the phase, 3 dof values; empty in closed form
  void assign(double time, const PhasePoint& point, const double* s, int n) {
    t = time;
    p = point;
    state.assign(s, s + n);  // keeps its capacity: no allocation per sample
  }
};

// State between two samples: quintic Hermite interpolation of each coordinate from (q, q', q'')
// at both ends, error O(h^6) in q and O(h^5) in q', below the integrator's own error.
struct HermiteSpan {
  const Sample* a;
  const Sample* b;
  int dof() const { return static_cast<int>(a->state.size() / 3); }
  void calc(double t, double* q, double* qd) const;
};

class PhasePeaks {
 public:
  void reset(double direction);
  // Besides the highest sample, each quantity keeps the earliest local maximum that the later ones
  // do not beat by more than this relative tolerance (the first of equal peaks; Extremum).
  void set_tie_tolerance(double tol) { tie_tol_ = tol; }
  // state: (q, q', q'') of the sample, 3 dof values (nullptr, 0 in closed form).
  void feed(double t, const PhasePoint& p, const double* state = nullptr, int n = 0);
  // eval(t, span) gives the phase point at t inside the span [a, b] of two consecutive samples.
  // first: the earliest of equal maxima, else the highest sample's. search false: the quantity is
  // the same at every instant of the phase, its best sample is its peak (no evaluation).
  template <class Eval>
  void refine(int q, bool first, Eval&& eval, double xtol, double& value, double& time, bool search = true) const;
  // The phase ended where a term of the loads grows without bound (a bay within 1e-4 l_s of
  // straight: G'(D) D'^2 ~ 1 / x^2), at the last sample fed, the event's own state: no span that
  // ends there is searched, since an interpolant of the state cannot resolve a load that steep
  // (a state error of 1e-15 m in D moves it by 1e-6 of itself); the stop's sample is taken as it is.
  void end_at_singularity() { singular_end_t_ = last_t_; }
  double best(int q) const { return b_[static_cast<std::size_t>(q)].top.value; }
  // Whether the earliest of equal maxima is another than the highest sample's.
  bool has_earlier_tie(int q) const {
    const Bracket& b = b_[static_cast<std::size_t>(q)];
    return b.first.value > -kInf && get(b.first, 1).t < get(b.top, 1).t;
  }
  double max_rail_residual = 0.0;

 private:
  // The last three samples stay in a ring; a hill refers to its samples by their number in the
  // phase and keeps its own copy only of one about to leave the ring (a quantity that keeps rising
  // copies nothing; a maximum copies its three samples once).
  static constexpr int kRing = 3;
  struct Hill {  // a local maximum's best sample and its neighbours
    double value = -kInf;
    std::array<long, 3> sample{-1, -1, -1};  // prev, best, next: their numbers while in the ring, else -1
    std::array<Sample, 3> own;               // ... and their copies once they left it
    bool want_next = false;
  };
  struct Bracket {
    Hill top, first;
    bool fell = false;  // a sample below first's best came after it: a later rise is another maximum
  };
  const Sample& get(const Hill& h, int which) const {
    const long i = h.sample[static_cast<std::size_t>(which)];
    return i >= 0 ? ring_[static_cast<std::size_t>(i % kRing)] : h.own[static_cast<std::size_t>(which)];
  }
  std::array<Bracket, kQuantityCount> b_;
  std::array<Sample, kRing> ring_;
  long count_ = 0;  // samples fed this phase
  double last_t_ = kNaN, singular_end_t_ = kNaN;  // the last sample's time; a singular end's (end_at_singularity)
  double direction_ = 1.0;
  double tie_tol_ = 0.0;
};

class PeakTracker {
 public:
  std::array<Extremum, kQuantityCount> run;  // run-wide
  Extremum stage_force, stage_pin;           // per stage
  Extremum stage_rail_approach;              // per stage, not merged into the run's
  double max_rail_residual = 0.0;
  int bay = 0;
  void set_tie_tolerance(double tol) {
    for (Extremum& e : run) e.tie_tol = tol;
    stage_force.tie_tol = stage_pin.tie_tol = stage_rail_approach.tie_tol = tol;
  }
  void start_stage(int b) { bay = b; stage_force.clear(); stage_pin.clear(); stage_rail_approach.clear(); }
  // The stage's force and pin records join the run's.
  void close_stage() {
    run[kForce].offer(stage_force.value, stage_force.t, stage_force.bay);
    run[kPin].offer(stage_pin.value, stage_pin.t, stage_pin.bay);
  }
  // Whether a phase whose largest value of quantity q is `best` can change its record.
  bool could_improve(int q, double best) {
    const Extremum& tr = target(q);
    return best > tr.largest() || !std::isfinite(tr.value);
  }
  Extremum& target(int q) {
    if (q == kForce) return stage_force;
    if (q == kPin) return stage_pin;
    if (q == kRailApproach) return stage_rail_approach;
    return run[static_cast<std::size_t>(q)];
  }
  // Refines each quantity of a finished phase whose best sample could beat the record; bit q of
  // constant set: quantity q is the same at every instant of the phase (not searched).
  template <class Eval>
  void absorb(const PhasePeaks& pp, Eval&& eval, double xtol, unsigned constant = 0) {
    max_rail_residual = std::max(max_rail_residual, pp.max_rail_residual);
    for (int q = 0; q < kQuantityCount; ++q) {
      Extremum& tr = target(q);
      if (!could_improve(q, pp.best(q))) continue;
      const bool search = !((constant >> q) & 1u);
      double v, t;
      if (pp.has_earlier_tie(q)) {  // the first of equal maxima, then the highest
        pp.refine(q, true, eval, xtol, v, t, search);
        tr.offer(v, t, bay);
      }
      pp.refine(q, false, eval, xtol, v, t, search);
      tr.offer(v, t, bay);
    }
  }
};

template <class Eval>
void PhasePeaks::refine(int q, bool first, Eval&& eval, double xtol, double& value, double& time, bool search) const {
  const Hill& b = first ? b_[static_cast<std::size_t>(q)].first : b_[static_cast<std::size_t>(q)].top;
  value = b.value;
  time = kNaN;
  if (!(b.value > -kInf)) return;  // no sample this phase
  const Sample& prev = get(b, 0);
  const Sample& best = get(b, 1);
  const Sample& next = get(b, 2);
  time = best.t;
  if (!std::isfinite(b.value) || !search) return;
  for (const HermiteSpan span : {HermiteSpan{&prev, &best}, HermiteSpan{&best, &next}}) {
    const double len = span.b->t - span.a->t;
    if (!(len > 0.0) || span.b->t == singular_end_t_) continue;
    // A best sample at a kink or at the phase end is often the maximum itself: if the quantity
    // falls just inside the span, the span holds nothing higher (it is bracketed by the grid).
    const bool best_is_a = span.a == &best;
    const double probe_t = best_is_a ? span.a->t + 1e-6 * len : span.b->t - 1e-6 * len;
    if (calc_peak_quantity(q, eval(probe_t, span), direction_) < b.value) continue;
    auto [tm, vm] = numerics::maximize_brent([&](double t) { return calc_peak_quantity(q, eval(t, span), direction_); },
                                             span.a->t, span.b->t, std::max(xtol, 1e-9 * len));
    if (vm > value) { value = vm; time = tm; }
  }
}

}  // namespace truss::stages
