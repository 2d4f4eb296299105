// The free stack (docs/model.md §2 "free") as a stack mode of the stage loop: the frames below the
// deploying bay move (their state: free_stack.hpp); every phase is stepped in time (phase_dynamic.hpp)
// on the phase models of free_phase.hpp and free_phase_b.hpp, in segments between the stop events
// that do not end it: stack contacts (a landing or a lift-off, then on) and the open phase's watched
// event, at most once: the hinge rising above the rail's top (its time is recorded). The other stop
// events are the stopping rules: rail miss, singular configuration.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include "free_stack/free_stack.hpp"
#include "stages/phase_dynamic.hpp"
#include "stages/stack_model.hpp"

namespace truss::stages {

class FreeStackModel final : public StackModel {
 public:
  FreeStackModel(const model::MastParams& mast, const RunnerOptions& opts, bool contacts);
  StackEvent start_stage(const StageSpec& s, bool first_stage) override;
  PhaseSegment begin_segment(const StageSpec& s, const PhaseSpec& ph, bool first, double t_s,
                             const integrators::IntegratorOptions& io) override;
  SegmentEnd end_segment(const PhaseOutcome& o, double t_s, const Extremum& closest) override;
  StackEvent end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint& p_end, double t_s) override;
  int find_first_moving_frame(const StageSpec&, const PhaseSpec&) const override {
    return std::max(stack_.get_last_lowest_frame(), 1);  // the phases carry every bay below the driven frame
  }
  double calc_end_potential_J(double /*stowed_J*/, double deployed_J) const override {
    return dir_ < 0 ? stack_.calc_potential_energy_J() : deployed_J;  // the free frames need not end stowed
  }
  int count_history_frames() const override { return mast_.n_bays() + 1; }
  void get_frame_heights(int m, double* y) const override { stack_.get_frame_heights(m, y); }

 private:
  StackEvent book_contacts(const FreeSegmentStart& c, double t_s) const;  // the contacts' event
  double calc_entry_margin_m();  // the rail margin of the entry that ends the open phase
  FreeStack stack_;
  std::unique_ptr<integrators::Integrator> integrator_;  // the run's one integrator
  PhaseContext ctx_;                                      // the phase running
  std::unique_ptr<PhaseModel> phase_;                     // its segment running
  std::optional<DynamicPhaseSolver> stepper_;
  std::vector<double> q0_, qdot0_;
  bool watch_rail_top_ = false;
  double rail_top_time_s_ = kNaN;  // the hinge rose above y_r (this stage)
};

}  // namespace truss::stages
