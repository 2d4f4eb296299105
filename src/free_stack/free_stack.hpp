// The free stack's state between phases and stages (docs/model.md §2 "free"): every frame's height and
// velocity, and the deploying bay's hinge offset on the rail. It builds the free phase models
// (free_phase.hpp, free_phase_b.hpp) with their start states, takes their end states back, and
// applies the stage events to the n frames: the velocity-mode start kick and the rail entry
// (model/free_impacts.hpp), and the lock (x = 0: bay m joins the locked part, dD/dt = 0 there).
// Moving frames: phase A lo = 1 (frame 0 held on the floor, as in the paper), the driven frame m
// on top; phase B lo = 1, or 0 in the stage of bay 1 (its rail lifts frame 0).
// Stack contacts (`stack.contacts = true`, free_stack/free_contacts.hpp): every contact D_i >= 0 starts
// closed; frames 0..k resting in closed contact on the floor (the resting block) are left out of
// the phases (lo = k + 1), frames in closed contact above move as clusters. prepare_segment opens
// every closed contact whose force pulls (before each integration segment), apply_contact_event
// applies a landing (plastic impact of the phase's coordinates, model/free_impacts.hpp) or a
// lift-off found by the phase's events.
#pragma once
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "model/free_impacts.hpp"
#include "model/params.hpp"
#include "free_stack/free_contacts.hpp"
#include "stages/phase.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

struct FreeRailEntry {
  model::StackImpact impact;
  double hinge_x_m = 0;
};

// What the start of an integration segment did to the contacts: pulling contacts opened,
// touching and closing ones landed (with the landings' loss and screw work).
struct FreeSegmentStart {
  int lift_offs = 0, landings = 0;
  double energy_loss_J = 0, drive_work_J = 0;
  bool ok = true;
  int bay = 0;
  bool handled = false;  // apply_contact_event: the stop event was a contact event
};

// What a contact event did: a landing's energy loss and drive impulse work (velocity drive).
struct FreeContactEvent {
  bool handled = false;  // the stop event was a contact event
  bool landing = false;
  bool ok = true;        // false: the landing impact has no solution
  double energy_loss_J = 0, drive_work_J = 0;
  int bay = 0;
  double impulse_Ns = 0;  // the contact (landing) or rail (unlock) impulse; the drive's for a start ramp
  double rail_impulse_Ns = std::numeric_limits<double>::quiet_NaN();  // unlock: the rail's impulse Lambda on the pins together (N s)
};

class FreeStack {
 public:
  // Baumgarte rate of the rail (and, in velocity mode, drive-speed) constraint on the rail (1/s):
  // about ten times the inverse of a stage's duration (~1 s at Table 1's 0.1 m/s), slow enough
  // for an explicit step of ~0.1 s to stay stable (DP5 stability ~3.3 / alpha).
  static constexpr double kBaumgarteRate_per_s = 10.0;
  int calc_lowest_frame(PhaseKind kind, int m) const;

  FreeStack(const model::MastParams& mast, bool contacts);
  // The phase model of ctx (ctx.kind, ctx.bay) on the current state; the open phase's watched
  // event (FreePhaseA::set_watch_rail_top): the hinge above the rail top.
  std::unique_ptr<PhaseModel> make_phase(const PhaseContext& ctx, bool watch_rail_top) const;
  // Rail function f of bay m's hinge at the current heights (m; > 0 before the rail).
  double calc_rail_function_m(int m) const;
  // Start state (q, q') of that phase, and its end state (q, q' concatenated) taken back.
  void get_start(const PhaseContext& ctx, std::vector<double>& q, std::vector<double>& qdot) const;
  void set_end(const PhaseContext& ctx, const std::vector<double>& end_state);
  // Velocity mode, t = 0: frames 1..m jump from rest with the driven frame at speed u (the kick),
  // or the driven frame alone (s.start_kick false: the paper's literal start).
  model::StackImpact apply_start_kick(const StageSpec& s, double u);
  // End of phase A of bay m: the plastic rail entry of all moving frames.
  FreeRailEntry apply_rail_entry(const StageSpec& s, bool drive_holds_speed);
  // End of phase B of bay m at x = 0: frame m is 2 l_m above frame m-1, with its velocity.
  void apply_lock(int m);
  // Hinge offset of bay i from the current heights (m), and the bay among 1..top with the smallest.
  double calc_hinge_offset_m(int i) const;
  int find_straightest_bay(int top) const;
  // Stack contacts: at a stage start, bay m deploys (its contact is no longer watched); before an
  // integration segment, open the pulling contacts (returns how many); after a stop event.
  void start_stage(int m);
  FreeSegmentStart prepare_segment(const PhaseContext& ctx, bool drive_holds_speed);
  FreeSegmentStart apply_contact_event(const PhaseContext& ctx, int stop_event, bool drive_holds_speed);
  int get_last_lowest_frame() const { return last_lo_; }
  // Retraction (docs/model.md §2, the reverse of deployment): the deployed mast at rest, frame 0 where
  // bay 1's rail left it (y_r - l_1), every bay straight, no contact closed.
  void init_deployed();
  // Unlock of bay m at x = 0: the plastic impact with the rail of frames lo..m-1 and the hinge
  // (docs/model.md §2: in velocity mode x' jumps to v tan(beta)); the screw keeps the driven speed, or
  // (from_rest, velocity drive) brings it to u as a lossless ramp whose work is the energy given.
  FreeContactEvent apply_unlock(const PhaseContext& ctx_on_rail, double u, bool drive_holds_speed, bool from_rest);
  // Rail exit of bay m (the held entry point: frame m-1 back at the stowed height 0): frame 0 lands
  // on the floor (m = 1) and, with contacts, frame m-1 on the resting stack (plastic); without
  // contacts frame m-1 (m >= 2) leaves the rail with its velocity (the paper's literal model).
  FreeContactEvent apply_rail_exit(const StageSpec& s, bool drive_holds_speed);
  double calc_potential_energy_J() const { return model::calc_potential_energy_J(mast_, y_.data()); }
  // Messages of the stopping rules (docs/model.md §2) at time t in the stage of bay m.
  std::string describe_singular(int m, double t_s) const;
  std::string describe_rail_miss(int m, bool past_miss_height, double closest_m, double closest_t_s, double rail_top_t_s, double t_s) const;
  double get_height_m(int k) const { return y_[static_cast<std::size_t>(k)]; }
  // Heights of frames 0..n with driven frame m (the frames above it locked rigid with it).
  void get_frame_heights(int m, double* y) const;
  double get_speed_m_per_s(int k) const { return v_[static_cast<std::size_t>(k)]; }

 private:
  model::ActiveFrames make_active(const StageSpec& s, int lo) const;
  ContactLayout make_layout(PhaseKind kind, int m, int lo) const;
  // Frame-height system of frames lo..m (bay m regular), reduced to the clusters of phase `kind`
  // with frame m alone; v: the cluster velocities.
  void calc_cluster_system(const StageSpec& s, PhaseKind kind, int lo, model::FrameSystem& sys, Eigen::VectorXd& v) const;
  void add_cluster_velocities(const ContactLayout& L, int lo, const Eigen::VectorXd& dv);
  ContactWatch watch_at(const PhaseContext& ctx) const;  // the contact events at the current state
  FreeContactEvent land(const PhaseContext& ctx, int bay, bool drive_holds_speed);  // plastic landing of bay's contact
  void open_contact(int j);
  const model::MastParams& mast_;
  std::vector<model::BayConstants> bays_;  // the bays' constants of the frame system (model/frames.hpp)
  const bool contacts_;
  std::vector<double> y_, v_;  // frames 0..n (frames above the driven one: not used)
  std::vector<char> closed_;   // contacts: closed_[i], bay i's contact D_i = 0 is closed
  int block_top_ = 0;          // contacts: frames 0..block_top_ rest on the floor
  mutable int last_lo_ = 1;    // lowest moving frame of the last phase built
  bool retract_ = false;       // retraction (init_deployed): in phase A bay m is a contact too
  double x_ = 0, xi_ = 0;      // hinge offset of the deploying bay on the rail and its rate
};

}  // namespace truss::stages
