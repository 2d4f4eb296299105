// Time-stepping solver of a phase (torque and motor drives): the PhaseModel's coordinates as a
// first-order ODE (q, q', W), W the drive work, through the run's Integrator; events are the
// phase end (rising end gap), a stop of the driven frame (falling speed) and, in motor mode, the
// creep stall. Peaks are refined on the Hermite interpolant of the step ends.
#pragma once
#include <memory>

#include "integrators/ode.hpp"
#include "stages/phase_solver.hpp"

namespace truss::stages {

// The phase as the solver integrates it: the ODE (q, q', W) and, when the model has one, its
// residual form with the band order IDA uses (for tests of that form).
std::unique_ptr<integrators::OdeSystem> make_phase_ode(const PhaseModel& model, double creep_speed_m_per_s);

class DynamicPhaseSolver final : public PhaseSolver {
 public:
  DynamicPhaseSolver(const PhaseModel& model, integrators::Integrator& integrator,
                     const integrators::IntegratorOptions& options)
      : model_(model), integrator_(integrator), options_(options) {}
  PhaseOutcome solve(const PhaseStart& start, PhaseSinks& sinks) override;
  // Below this fraction of a reference speed the mast has stopped for any engineering purpose
  // (the rest of the stage would take ~1e6 times its nominal time): motor mode, the no-load screw
  // speed; torque mode, the fastest driven speed of the run so far (frictionless, a torque-driven
  // mast only creeps when it approaches an equilibrium or a singular configuration).
  static constexpr double kCreepSpeedFraction = 1e-6;
  static double calc_creep_speed_m_per_s(const model::DriveParams& d);
  // A phase still running after this much simulated time (116 days) deploys too slowly for any
  // mission: the run ends as a stall (a creeping drive), not by a cap.
  static constexpr double kHorizon_s = 1e7;

 private:
  const PhaseModel& model_;
  integrators::Integrator& integrator_;
  integrators::IntegratorOptions options_;  // with the run's remaining step budget
};

}  // namespace truss::stages
