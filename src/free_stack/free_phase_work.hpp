// Work space of a free-stack phase's evaluations (phases A and B): the expanded frame heights and
// velocities, the system reduced to clusters, the bordered terms and the solves. Each phase owns
// one, built with the phase for its stage of one run, so that an evaluation allocates nothing once
// the sizes are reached and no state is shared between runs or threads (a phase is evaluated by
// one thread at a time). Its contents are scratch: no value carries from one evaluation to the next.
#pragma once
#include <vector>

#include <Eigen/Core>

#include "model/tridiagonal.hpp"
#include "free_stack/free_contacts.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

struct FreePhaseWork {
  std::vector<double> ys, vs;              // events, touches, frame heights, contact watch
  std::vector<double> point_ys, point_vs;  // the evaluation (calc_point, calc_motion, residual form)
  std::vector<double> zero;                // zero velocities (frame heights alone)
  Eigen::VectorXd rhs, diag, sub, rhs_reduced, acc;  // the system, reduced to clusters, its solution
  PhaseDaeTerms terms;                     // phase B's bordered terms
  model::TridiagonalWork solve;
  ContactWatchWork contact;
};

}  // namespace truss::stages
