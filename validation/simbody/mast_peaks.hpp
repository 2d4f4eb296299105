// Peaks of the smooth motion (docs/model.md §5: loads between the impulses, not the impulses).
// Every sample (step ends, the states just before and after each event) is a candidate. Between
// events the motion is smooth; where three consecutive samples of such a segment bracket a local
// maximum that could beat the stage's peak, the bracket is re-integrated from its first sample
// (mast_run.cpp, `refinePeak`) on a grid of 8 points, then of 8 points around the best one, without
// interpolation, and the parabola through the best three grid points gives the peak. Steps of a
// kinematic (velocity-mode held) run are long (0.2 s); a parabola through the step ends alone
// missed the pin force's peak by 6.7e-5 of it.
#pragma once
#include <array>

#include "Simbody.h"

namespace mastcheck {

// Vertex of the parabola through (t[i], v[i]), i = 0..2 (t increasing): false unless it is a
// maximum inside [t[0], t[2]].
inline bool calc_parabola_peak(const double t[3], const double v[3], double& t_peak, double& v_peak) {
  const double h0 = t[1] - t[0], h1 = t[2] - t[1];
  const double d0 = (v[1] - v[0]) / h0, d1 = (v[2] - v[1]) / h1;
  const double curvature = (d1 - d0) / (h0 + h1);  // v = v1 + slope (t - t1) + curvature (t - t1)^2
  if (!(curvature < 0)) return false;
  const double slope = d0 + curvature * h0;
  const double dt = -slope / (2 * curvature);
  if (dt < -h0 || dt > h1) return false;
  t_peak = t[1] + dt;
  v_peak = v[1] + slope * dt + curvature * dt * dt;
  return true;
}

// The last three samples of the current smooth segment: time, state and the sampled signals.
inline constexpr int kSignals = 3;  // 0: drive force, 1: pin force, 2: diagonal tension
struct Sample {
  double t = 0;
  SimTK::Vector q, u;
  std::array<double, kSignals> value{};
};

class SegmentSamples {
 public:
  // False (and nothing kept) for a second sample at the same instant (an event's post-state).
  bool add(Sample sample) {
    if (n_ > 0 && sample.t <= s_[n_ - 1].t) return false;
    if (n_ == 3) { s_[0] = std::move(s_[1]); s_[1] = std::move(s_[2]); n_ = 2; }
    s_[n_++] = std::move(sample);
    return true;
  }
  void clear() { n_ = 0; }
  // Three samples with the middle one a local maximum of signal k.
  bool bracketsMaximum(int k) const {
    return n_ == 3 && s_[1].value[k] >= s_[0].value[k] && s_[1].value[k] > s_[2].value[k];
  }
  const Sample& operator[](int i) const { return s_[i]; }

 private:
  std::array<Sample, 3> s_;
  int n_ = 0;
};

}  // namespace mastcheck
