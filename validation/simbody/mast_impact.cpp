#include "mast_impact.hpp"

namespace mastcheck {
using namespace SimTK;

ImpactResult apply_plastic_impact(const MultibodySystem& system, const SimbodyMatterSubsystem& matter, State& s,
                                  const Vector& u_before) {
  // A velocity lock records its speed but sets u only when prescribed (a position lock sets both).
  system.realize(s, Stage::Time);
  system.prescribeQ(s);
  system.realize(s, Stage::Position);
  system.prescribeU(s);
  // What the locks prescribe pushes on the free mobilities through the mass matrix coupling.
  const Vector du_prescribed = s.getU() - u_before;
  Vector coupling, du_free;
  matter.multiplyByM(s, du_prescribed, coupling);
  coupling *= -1;
  matter.multiplyByMInv(s, coupling, du_free);  // free part; prescribed entries come back 0
  s.updU() += du_free;

  // Then the constraint impulses remove what is left of the velocity errors.
  ImpactResult result;
  result.constraint_impulse.resize(s.getNU());
  result.constraint_impulse = 0;
  if (s.getNUDotErr() > 0) {
    system.realize(s, Stage::Velocity);
    const Vector& verr = s.getUErr();
    Vector delta_v(s.getNUDotErr(), Real(0));
    for (int i = 0; i < verr.size(); ++i) delta_v[i] = -verr[i];
    matter.solveForConstraintImpulses(s, delta_v, result.impulse);
    Vector du;
    matter.multiplyByGTranspose(s, result.impulse, result.constraint_impulse);
    matter.multiplyByMInv(s, result.constraint_impulse, du);
    s.updU() += du;
  }

  system.realize(s, Stage::Velocity);
  const Vector jump = s.getU() - u_before;
  matter.multiplyByM(s, jump, result.mobility_impulse);
  result.energy_lost_J = 0.5 * (~jump * result.mobility_impulse);
  return result;
}

}  // namespace mastcheck
