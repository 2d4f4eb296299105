#include "free_stack/free_stack_model.hpp"

#include <cmath>

#include <fmt/format.h>

#include "integrators/factory.hpp"
#include "free_stack/free_phase.hpp"

namespace truss::stages {

FreeStackModel::FreeStackModel(const model::MastParams& mast, const RunnerOptions& opts, bool contacts)
    : StackModel(mast, opts), stack_(mast, contacts),
      integrator_(integrators::make_integrator(opts.run.integrator, opts.calc_integrator_options())) {
  if (dir_ < 0) stack_.init_deployed();
}

StackEvent FreeStackModel::book_contacts(const FreeSegmentStart& c, double t_s) const {
  StackEvent e;
  e.contact_lift_offs = c.lift_offs;
  e.contact_landings = c.landings;
  e.energy_loss_J = c.energy_loss_J;
  e.drive_work_J = c.drive_work_J;  // the screw's work in the landings (velocity drive)
  if (!c.ok)
    e.failure = fmt::format("singular configuration: the landing of frame {} at t = {:.9g} s (stage of bay {}) has no "
                            "plastic solution", c.bay, t_s, ctx_.bay);
  return e;
}

StackEvent FreeStackModel::start_stage(const StageSpec& s, bool first_stage) {
  rail_top_time_s_ = kNaN;
  stack_.start_stage(s.bay);
  StackEvent e;
  const double u = dir_ * opts_.drive.speed_m_per_s;
  if (s.start == StageStart::unlock) {  // retraction: unlock of bay m with every moving frame (docs/model.md §2)
    const PhaseContext ctx = make_context(s, PhaseKind::on_rail, 0.0);
    const FreeContactEvent c = stack_.apply_unlock(ctx, u, drive_holds_speed_, first_stage);
    if (!c.ok) e.failure = fmt::format("singular configuration: the unlock of bay {} has no solution", s.bay);
    if (!c.ok) return e;
    if (first_stage && drive_holds_speed_) e.start_drive_impulse_Ns = c.impulse_Ns;
    e.rail_impulse_Ns = c.rail_impulse_Ns;
    e.energy_loss_J = c.energy_loss_J;
    e.drive_work_J = c.drive_work_J;
    return e;
  }
  if (s.start != StageStart::from_rest_or_kick || !drive_holds_speed_) return e;
  // Impulsive start (docs/model.md §2 "free"): the free frames take the momentum-consistent kick,
  // or stay at rest (stack.start = "rest").
  const model::StackImpact k = stack_.apply_start_kick(s, u);
  if (!k.ok) e.failure = "singular configuration: the stowed stack's mass matrix is not positive definite";
  if (!k.ok) return e;
  e.start_drive_impulse_Ns = k.drive_impulse_Ns;
  e.drive_work_J = k.drive_work_J;
  return e;
}

PhaseSegment FreeStackModel::begin_segment(const StageSpec& s, const PhaseSpec& ph, bool first, double t_s,
                                           const integrators::IntegratorOptions& io) {
  if (first) {
    ctx_ = make_context(s, ph.kind, 0.0);
    ctx_.q_end = dir_ > 0 ? 0.0 : ph.q_end;  // on the rail: the lock at x = 0 (x falling), or the exit
    ctx_.sign_q = ph.kind == PhaseKind::on_rail ? -dir_ : dir_;
    watch_rail_top_ = ph.kind == PhaseKind::open && dir_ > 0;
  }
  PhaseSegment seg;
  // Open the pulling contacts, land the touching ones.
  seg.start_events = book_contacts(stack_.prepare_segment(ctx_, drive_holds_speed_), t_s);
  if (!seg.start_events.failure.empty()) return seg;
  phase_ = stack_.make_phase(ctx_, watch_rail_top_);
  stack_.get_start(ctx_, q0_, qdot0_);
  seg.solver = &stepper_.emplace(*phase_, *integrator_, io);
  seg.q = q0_.data();
  seg.qdot = qdot0_.data();  // creep reference: the run's peak speed alone (creep_reference_m_per_s 0)
  return seg;
}

SegmentEnd FreeStackModel::end_segment(const PhaseOutcome& o, double t_s, const Extremum& closest) {
  SegmentEnd r;
  if (!o.end_state.empty()) stack_.set_end(ctx_, o.end_state);
  if (o.reason != PhaseEndReason::model_stop) return r;
  const FreeSegmentStart c = stack_.apply_contact_event(ctx_, o.stop_event, drive_holds_speed_);
  r.next = SegmentEnd::Next::next_segment;
  if (c.handled) {  // stack contacts: a landing or a lift-off, then on
    r.event = book_contacts(c, t_s);
    return r;
  }
  if (watch_rail_top_ && o.stop_event == FreePhaseA::above_rail_top) {
    rail_top_time_s_ = t_s;  // recorded; the phase goes on without this event
    watch_rail_top_ = false;
    return r;
  }
  r.next = SegmentEnd::Next::failed;
  const int m = ctx_.bay;
  if (ctx_.kind == PhaseKind::on_rail || o.stop_event == FreePhaseA::singular_bay) {
    r.status = RunStatus::singular_configuration;
    r.message = stack_.describe_singular(m, t_s);
    return r;
  }
  r.status = RunStatus::rail_miss;
  r.above_rail_top_time_s = rail_top_time_s_;
  r.message = stack_.describe_rail_miss(m, o.stop_event == FreePhaseA::past_miss_height, -closest.value, closest.t,
                                        rail_top_time_s_, t_s);
  return r;
}

StackEvent FreeStackModel::end_phase(const StageSpec& s, const PhaseSpec& ph, const PhasePoint&, double t_s) {
  StackEvent e;
  switch (ph.end) {
    case PhaseEnd::rail_exit: {  // retraction: frame m-1 lands on the floor or the resting stack
      const FreeContactEvent c = stack_.apply_rail_exit(s, drive_holds_speed_);
      if (!c.ok) e.failure = fmt::format("singular configuration: the rail exit of bay {} has no solution", s.bay);
      if (!c.ok) return e;
      e.landing_impulse_Ns = std::abs(c.impulse_Ns);
      e.drive_impulse_Ns = 0.0;
      e.energy_loss_J = c.energy_loss_J;
      e.drive_work_J = c.drive_work_J;
      return e;
    }
    case PhaseEnd::rail_entry: {  // plastic impact of all moving frames with the rail (model/free_impacts.hpp)
      e.rail_margin_m = calc_entry_margin_m();  // before the impact changes the velocities
      ++e.evals;
      const FreeRailEntry r = stack_.apply_rail_entry(s, drive_holds_speed_);
      if (!r.impact.ok)
        e.failure = fmt::format("singular configuration: the rail entry of bay {} at t = {:.9g} s has no solution", s.bay, t_s);
      if (!r.impact.ok) return e;
      e.rail_impulse_Ns = r.impact.rail_impulse_Ns;
      e.drive_impulse_Ns = r.impact.drive_impulse_Ns;
      e.energy_loss_J = r.impact.energy_loss_J;
      e.drive_work_J = r.impact.drive_work_J;
      return e;
    }
    case PhaseEnd::lock: stack_.apply_lock(s.bay); return e;  // frame m 2 l_m above frame m-1, with its velocity
    case PhaseEnd::reach_height: return e;                      // retraction: frame m back at its start height
  }
  return e;
}

double FreeStackModel::calc_entry_margin_m() {
  const auto* a = dynamic_cast<const FreePhaseA*>(phase_.get());
  if (a == nullptr) return kNaN;
  stack_.get_start(ctx_, q0_, qdot0_);  // the state at the entry (set_end)
  std::vector<double> qddot(q0_.size());
  PhaseScratch scratch;
  a->calc_point(q0_.data(), qdot0_.data(), qddot.data(), scratch);
  return a->calc_rail_entry_margin_m(q0_.data(), qdot0_.data(), qddot.data());
}

}  // namespace truss::stages
