// The held stack (docs/model.md §2): the canister holds the frames below the deploying bay, so a
// phase moves one coordinate (held_phase.hpp) and the driven frame's velocity u and the hinge
// speed xi carry over between phases. Its events are those of two frames (model/impacts.hpp): the
// drive's lossless start ramp, the unlock, the rail entry and the rail exit. A phase is one
// segment: closed form in velocity mode (phase_kinematic.hpp), stepped in time otherwise
// (phase_dynamic.hpp).
#pragma once
#include <algorithm>
#include <memory>
#include <optional>

#include "stages/held_phase.hpp"
#include "stages/phase_dynamic.hpp"
#include "stages/phase_kinematic.hpp"
#include "stages/stack_model.hpp"

namespace truss::stages {

class HeldStack final : public StackModel {
 public:
  HeldStack(const model::MastParams& mast, const RunnerOptions& opts);
  StackEvent start_stage(const StageSpec& s, bool first_stage) override;
  PhaseSegment begin_segment(const StageSpec& s, const PhaseSpec& ph, bool first, double t_s,
                             const integrators::IntegratorOptions& io) override;
  SegmentEnd end_segment(const PhaseOutcome&, double, const Extremum&) override { return {}; }  // no stop events
  StackEvent end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, double t_s) override;
  int find_first_moving_frame(const StageSpec& s, const PhaseSpec& ph) const override {
    return ph.kind == PhaseKind::on_rail ? std::max(s.bay - 1, 1) : s.bay;
  }

 private:
  const model::RailConstants rail_;                       // the rail's trigonometry, once a run
  std::unique_ptr<integrators::Integrator> integrator_;  // the run's one integrator (torque, motor)
  std::optional<HeldPhase> phase_;                        // the phase running
  std::optional<KinematicPhaseSolver> closed_form_;
  RatedPeakWork peak_work_;  // closed_form_'s work space, kept for the run's phases
  std::optional<DynamicPhaseSolver> stepper_;
  double u_ = 0;             // driven-frame velocity carried between stages
  double xi_ = 0;            // hinge speed carried between phases
  double q0_ = 0, qdot0_ = 0;  // start state of the phase running
};

}  // namespace truss::stages
