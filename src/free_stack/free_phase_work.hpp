// Work space of a free-stack phase's evaluations (phases A and B): the expanded frame heights and
// velocities, the system reduced to clusters, the bordered terms and the solves. Each phase owns
// one, built with the phase for its stage of one run, so that an evaluation allocates nothing once
// the sizes are reached and no state is shared between runs or threads (a phase is evaluated by
// one thread at a time). Its contents are scratch: no value carries from one evaluation to the next.
#pragma once
#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "model/tridiagonal.hpp"
#include "free_stack/free_contacts.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

// The last solved state of a phase and what its solve gave: the accelerations, the drive force,
// the rail's multiplier. One state is asked for several times in a row (the integrator's last
// stage at a step's end, the events there, the step-end sample of the peaks, the contact watch),
// and a state equal bit for bit is answered from here, with the same bits as a new solve; the
// phase's work space (terms, heights) still holds that solve. Anything else that writes the work
// space clears it. The caller's scratch is work space, not output, with two readers: phase A's
// point reads its mass matrix from the frame-level system there, and the contact watch reads that
// system; so phase A, and phase B with stack contacts on, keep a copy of it in the memo
// (keep_system), which a hit puts back.
struct MotionMemo {
  bool valid = false, keep_system = false;
  std::vector<double> state, qddot;  // (q, q') and q''
  double drive_force_N = 0, lambda_N = 0;
  PhaseScratch sys;
  bool matches(const double* q, const double* qdot, int n) const {
    if (!valid || static_cast<int>(qddot.size()) != n) return false;
    const double* s = state.data();
    for (int i = 0; i < n; ++i)
      if (!(s[i] == q[i]) || !(s[n + i] == qdot[i])) return false;
    return true;
  }
  void store(const double* q, const double* qdot, const double* a, int n, const PhaseScratch& s) {
    state.resize(static_cast<std::size_t>(2 * n));
    qddot.resize(static_cast<std::size_t>(n));
    std::copy(q, q + n, state.begin());
    std::copy(qdot, qdot + n, state.begin() + n);
    std::copy(a, a + n, qddot.begin());
    if (keep_system) sys = s;
    valid = true;
  }
  // On a hit: the frame-level system of the memo's state into the caller's scratch (when kept).
  void restore_system(PhaseScratch& s) const {
    if (keep_system && &s != &sys) s = sys;
  }
};

struct FreePhaseWork {
  std::vector<double> ys, vs;              // events, touches, frame heights, contact watch
  std::vector<double> point_ys, point_vs;  // the evaluation (calc_point, calc_motion, residual form)
  std::vector<double> zero;                // zero velocities (frame heights alone)
  Eigen::VectorXd rhs, diag, sub, rhs_reduced, acc;  // the system, reduced to clusters, its solution
  PhaseDaeTerms terms;                     // phase B's bordered terms
  model::TridiagonalWork solve;
  ContactWatchWork contact;
  MotionMemo memo;  // the last solve (see above)
};

}  // namespace truss::stages
