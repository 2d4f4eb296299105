// Closed-form solver of a held phase in velocity mode (docs/model.md §2; paper: constant speed):
// the driven frame moves at direction * v, so y_m is linear in time; on the rail x follows from
// the remaining travel to the lock without cancellation (model/rail.hpp). The drive force comes
// from inverse dynamics; its peaks are bracketed on a grid per smooth piece (split where bay m's
// diagonals become taut, a kink) and refined by Brent's method on the exact closed form; the
// drive work is the Gauss-Kronrod integral of F u. No time stepping.
#pragma once
#include "stages/held_phase.hpp"
#include "stages/phase_solver.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

class KinematicPhaseSolver final : public PhaseSolver {
 public:
  KinematicPhaseSolver(const HeldPhase& phase, const PhaseSpec& spec, int samples_per_piece)
      : phase_(phase), spec_(spec), samples_per_piece_(samples_per_piece) {}
  PhaseOutcome solve(const PhaseStart& start, PhaseSinks& sinks) override;

 private:
  const HeldPhase& phase_;
  const PhaseSpec& spec_;
  int samples_per_piece_;
};

}  // namespace truss::stages
