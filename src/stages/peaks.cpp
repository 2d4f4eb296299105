#include "stages/peaks.hpp"

#include <algorithm>

namespace truss::stages {

void HermiteSpan::calc(double t, double* q, double* qd) const {
  const int n = dof();
  const double h = b->t - a->t, s = (t - a->t) / h, s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
  for (int i = 0; i < n; ++i) {
    const double qa = a->state[i], va = h * a->state[n + i], aa = h * h * a->state[2 * n + i];
    const double qb = b->state[i], vb = h * b->state[n + i], ab = h * h * b->state[2 * n + i];
    q[i] = (1 - 10 * s3 + 15 * s4 - 6 * s5) * qa + (s - 6 * s3 + 8 * s4 - 3 * s5) * va +
           (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * aa + (10 * s3 - 15 * s4 + 6 * s5) * qb +
           (-4 * s3 + 7 * s4 - 3 * s5) * vb + (0.5 * s3 - s4 + 0.5 * s5) * ab;
    qd[i] = ((-30 * s2 + 60 * s3 - 30 * s4) * qa + (1 - 18 * s2 + 32 * s3 - 15 * s4) * va +
             (s - 4.5 * s2 + 6 * s3 - 2.5 * s4) * aa + (30 * s2 - 60 * s3 + 30 * s4) * qb +
             (-12 * s2 + 28 * s3 - 15 * s4) * vb + (1.5 * s2 - 4 * s3 + 2.5 * s4) * ab) / h;
  }
}

void PhasePeaks::reset(double direction) {
  for (Bracket& b : b_) {
    for (Hill* h : {&b.top, &b.first}) {
      h->value = -kInf;
      h->want_next = false;
      h->sample = {-1, -1, -1};
    }
    b.fell = false;
  }
  count_ = 0;
  last_t_ = singular_end_t_ = kNaN;
  direction_ = direction;
  max_rail_residual = 0.0;
}

void PhasePeaks::feed(double t, const PhasePoint& p, const double* state, int n) {
  const long i = count_++;
  Sample& slot = ring_[static_cast<std::size_t>(i % kRing)];
  if (i >= kRing)  // sample i - kRing leaves the ring: the hills that refer to it copy it
    for (Bracket& b : b_)
      for (Hill* h : {&b.top, &b.first})
        for (std::size_t w = 0; w < 3; ++w)
          if (h->sample[w] == i - kRing) { h->own[w] = slot; h->sample[w] = -1; }
  slot.assign(t, p, state, n);
  last_t_ = t;
  for (int q = 0; q < kQuantityCount; ++q) {
    Bracket& b = b_[static_cast<std::size_t>(q)];
    const double v = calc_peak_quantity(q, p, direction_);
    auto take = [&](Hill& h, bool better) {
      if (better) {
        h.value = v;
        h.sample = {i > 0 ? i - 1 : i, i, i};  // the previous sample (itself at the phase start), this, the next
        h.want_next = true;
      } else if (h.want_next) {
        h.sample[2] = i;
        h.want_next = false;
      }
    };
    take(b.top, v > b.top.value);
    // A rise after a fall is another local maximum: it replaces the first only beyond the tie
    // tolerance (the earliest of equal peaks is kept).
    const bool first = v > b.first.value && !(b.fell && is_tie(b.first.value, v, tie_tol_));
    take(b.first, first);
    b.fell = !first && (b.fell || v < b.first.value);
  }
  max_rail_residual = std::max(max_rail_residual, p.rail_residual_m);
}

}  // namespace truss::stages
