// Stack contacts of the free phases (docs/model.md §2 "free", `stack.contacts = true`; equations in
// model/contacts.hpp). The frames lo..top of a phase (top = m in phase A, m - 1 in phase B) form
// clusters of frames in closed contact; frames 0..lo-1 rest on the floor in closed contact (the
// resting block, at height 0) and are not in the system at all: a phase costs O(moving frames).
// A phase watches two contact events, each rising through zero:
//   landing   max over open contacts i (cluster bottoms lo..top, not the deploying bay m unless
//             the driven frame comes down onto frame m - 1 in a retraction) of
//             -D_i - kGapTolerance l_i: a frame reaches the one below it (or the resting block);
//   lift_off  max over closed contacts of -lambda_j - kForceTolerance_N: the resting block's top
//             frame (when it is not frame 0, held on the floor as in the paper) or a frame inside a
//             moving cluster starts to pull away.
// The tolerances keep an event from firing at the instant the contact was just made or broken
// (the gap starts at 0, the force at 0) and are far below the integration error of the heights.
#pragma once
#include <algorithm>
#include <vector>

#include "model/frames.hpp"
#include "model/params.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

struct ContactLayout {
  static constexpr double kGapTolerance = 1e-9;     // of the bay's l_s
  static constexpr double kForceTolerance_N = 1e-9;  // N
  bool enabled = false;         // contacts on: clusters and the two events
  std::vector<int> starts;      // first local frame (frame - lo) of each cluster, of frames lo..top
  int frames = 0;               // top - lo + 1
  bool block_liftable = false;  // frame lo - 1 >= 1 rests on the block: its lift-off is watched
  bool driven_contact = false;  // retraction, phase A: the driven frame m may land on frame m - 1
  bool reduces() const { return enabled && static_cast<int>(starts.size()) != frames; }
  int clusters() const { return enabled ? static_cast<int>(starts.size()) : frames; }
  // Cluster values (one per cluster) to frame values (frames lo..top).
  void expand(const double* cluster, double* frame) const {
    if (enabled) expand_clusters(cluster, frame);
    else std::copy(cluster, cluster + frames, frame);  // one frame a cluster
  }

 private:
  void expand_clusters(const double* cluster, double* frame) const;
};

// The watched contact quantities at one state (see above) and where they are.
struct ContactWatch {
  double landing_g = -1.0, lift_off_g = -1.0;
  int landing_bay = 0, lift_off_bay = 0;  // bay of the contact (its upper frame)
  // An open contact touching (D_i <= 0) and closing (dD_i/dt < 0), the fastest closing one: the
  // contact to land (several can touch at one event; a touching one may start a segment).
  int touching_bay = 0;
};

// ys, vs: heights and velocities of frames first.. (first = max(lo - 1, 0)); sys: the frame-level
// system of frames lo..; a: accelerations of frames lo..top; m: the deploying bay.
ContactWatch calc_contact_watch(const model::MastParams& mast, const ContactLayout& layout, int lo, int m,
                                const double* ys, const double* vs, int first, const model::FrameSystem& sys,
                                const double* a);
// Work space of the watch below, owned by the phase that calls it: the phase's evaluation and the
// frames' accelerations.
struct ContactWatchWork {
  PhaseScratch sys;
  std::vector<double> acc, a;
};
// The same for a free phase at (q, q'): the accelerations from the phase's own evaluation
// (calc_motion), so that the watched contact forces are those of the motion being integrated.
// ys, vs: the phase's frame heights and velocities at (q, q') as above.
ContactWatch calc_contact_watch(const PhaseModel& phase, const ContactLayout& layout, int lo, const double* q,
                                const double* qdot, const double* ys, const double* vs, ContactWatchWork& work);

}  // namespace truss::stages
