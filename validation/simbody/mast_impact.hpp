// The plastic impact of docs/model-notes.md ("Stages and impacts"): after an event has changed
// the constraint set (a rail enabled, mobilizers locked or released, a drive speed prescribed),
// the speeds jump to the motion that satisfies the new constraints with the least kinetic energy
// change, i.e. the solution of
//
//     M du = ~G Lambda + (impulses on the prescribed mobilities),   G (u + du) = b,
//     du_p = the change the new locks prescribe,
//
// and the energy lost is du' M du / 2 (Carnot). Solved with Simbody's O(n) operators on the free
// mobilities: du_f = -M_ff^-1 (M du_p)_f, then the constraint impulses W Lambda = -verr
// (SimbodyMatterSubsystem::solveForConstraintImpulses) and du_f += M_ff^-1 ~G Lambda.
#pragma once
#include "Simbody.h"

namespace mastcheck {

struct ImpactResult {
  SimTK::Vector impulse;          // constraint-space impulses Lambda (N s, per constraint equation)
  SimTK::Vector mobility_impulse; // M du: the impulse on every mobility (N s or N m s)
  SimTK::Vector constraint_impulse;  // ~G Lambda: the constraints' part of it
  double energy_lost_J = 0;
  // The impulse that held a prescribed mobility at its speed (a drive's, a lock's).
  double findPrescribedImpulse(SimTK::UIndex u) const { return mobility_impulse[u] - constraint_impulse[u]; }
};

// `u_before`: the speeds before the event changed anything. `s` holds the new locks and
// constraints (and the speeds the locks set); its speeds are replaced by the post-impact ones.
ImpactResult apply_plastic_impact(const SimTK::MultibodySystem& system, const SimTK::SimbodyMatterSubsystem& matter,
                                  SimTK::State& s, const SimTK::Vector& u_before);

}  // namespace mastcheck
