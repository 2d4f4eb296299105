// Closed-form solver of a held phase in velocity mode (docs/model.md §2; paper: constant speed):
// the driven frame moves at direction * v, so y_m is linear in time; on the rail x follows from
// the remaining travel to the lock without cancellation (model/rail.hpp). The drive force comes
// from inverse dynamics; its peaks are bracketed on a grid per smooth piece (split where bay m's
// diagonals become taut, a kink) and refined by Brent's method on the exact closed form; the
// drive work is the Gauss-Kronrod integral of F u. No time stepping.
#pragma once
#include "stages/held_phase.hpp"
#include "stages/phase_solver.hpp"

namespace truss::stages {

class KinematicPhaseSolver final : public PhaseSolver {
 public:
  KinematicPhaseSolver(const HeldPhase& phase, int samples_per_piece) : phase_(phase), samples_per_piece_(samples_per_piece) {}
  // From start.q (the phase coordinate at its start; start.qdot is the prescribed kinematics) to
  // the phase's end context().q_end.
  PhaseOutcome solve(const PhaseStart& start, PhaseSinks& sinks) override;

 private:
  const HeldPhase& phase_;
  int samples_per_piece_;
};

}  // namespace truss::stages
