// Closed-form solver of a held phase in velocity mode (docs/model.md §2; paper: constant speed):
// the driven frame moves at direction * v, so y_m is linear in time; on the rail x follows from
// the remaining travel to the lock without cancellation (model/rail.hpp). No time stepping.
// Every evaluation is in dual numbers (numerics/dual.hpp): the drive force from inverse
// dynamics, the pin force, the tensions and their exact time derivatives. Each smooth piece
// (split where bay m's diagonals become taut, a kink) is sampled on a grid; a quantity's peak is
// a grid value, or the root of its time derivative where that changes sign from + to - between
// two grid points (or where their cubic Hermite interpolant has a maximum inside), found by a
// safeguarded secant to the rounding level (closed_form_peaks.hpp). The drive work of the phase
// is the change of its mechanical energy between its end points (docs/model-notes.md, "Drive
// work in velocity mode"): the rail and the held frames do no work.
#pragma once
#include "stages/closed_form_peaks.hpp"
#include "stages/held_phase.hpp"
#include "stages/phase_solver.hpp"

namespace truss::stages {

class KinematicPhaseSolver final : public PhaseSolver {
 public:
  // work: the run's peak-search work space (reused phase after phase).
  KinematicPhaseSolver(const HeldPhase& phase, int samples_per_piece, RatedPeakWork& work)
      : phase_(phase), samples_per_piece_(samples_per_piece), work_(work) {}
  // From start.q (the phase coordinate at its start; start.qdot is the prescribed kinematics) to
  // the phase's end context().q_end.
  PhaseOutcome solve(const PhaseStart& start, PhaseSinks& sinks) override;

 private:
  const HeldPhase& phase_;
  int samples_per_piece_;
  RatedPeakWork& work_;
};

}  // namespace truss::stages
