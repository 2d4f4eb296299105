// The free stack's state between phases and stages (MODEL.md 2 "free"): every frame's height and
// velocity, and the deploying bay's hinge offset on the rail. It builds the free phase models
// (free_phase.hpp, free_phase_b.hpp) with their start states, takes their end states back, and
// applies the stage events to the n frames: the velocity-mode start kick and the rail entry
// (model/free_impacts.hpp), and the lock (x = 0: bay m joins the locked part, dD/dt = 0 there).
// Moving frames: phase A lo = 1 (frame 0 held on the floor, as in the paper), the driven frame m
// on top; phase B lo = 1, or 0 in the stage of bay 1 (its rail lifts frame 0).
#pragma once
#include <memory>
#include <vector>

#include "model/free_impacts.hpp"
#include "model/params.hpp"
#include "stages/phase.hpp"
#include "stages/stage_plan.hpp"

namespace truss::stages {

struct FreeRailEntry {
  model::StackImpact impact;
  double hinge_x_m = 0;
};

class FreeStack {
 public:
  // Baumgarte rate of the rail (and, in velocity mode, drive-speed) constraint on the rail (1/s):
  // about ten times the inverse of a stage's duration (~1 s at Table 1's 0.1 m/s), slow enough
  // for an explicit step of ~0.1 s to stay stable (DP5 stability ~3.3 / alpha).
  static constexpr double kBaumgarteRate_per_s = 10.0;
  static int calc_lowest_frame(PhaseKind kind, int m) { return kind == PhaseKind::open || m >= 2 ? 1 : 0; }

  explicit FreeStack(const model::MastParams& mast);
  // The phase model of ctx (ctx.kind, ctx.bay) on the current state; the open phase's watched
  // events (FreePhaseA::set_watch): the hinge above the rail top, the minimum of f.
  std::unique_ptr<PhaseModel> make_phase(const PhaseContext& ctx, bool watch_rail_top, bool watch_approach_min) const;
  // Rail function f of bay m's hinge at the current heights (m; > 0 before the rail).
  double calc_rail_function_m(int m) const;
  // Start state (q, q') of that phase, and its end state (q, q' concatenated) taken back.
  void get_start(const PhaseContext& ctx, std::vector<double>& q, std::vector<double>& qdot) const;
  void set_end(const PhaseContext& ctx, const std::vector<double>& end_state);
  // Velocity mode, t = 0: frames 1..m jump from rest with the driven frame at speed u.
  model::StackImpact apply_start_kick(const StageSpec& s, double u);
  // End of phase A of bay m: the plastic rail entry of all moving frames.
  FreeRailEntry apply_rail_entry(const StageSpec& s, bool drive_holds_speed);
  // End of phase B of bay m at x = 0: frame m is 2 l_m above frame m-1, with its velocity.
  void apply_lock(int m);
  // Hinge offset of bay i from the current heights (m), and the bay among 1..top with the smallest.
  double calc_hinge_offset_m(int i) const;
  int find_straightest_bay(int top) const;
  double get_height_m(int k) const { return y_[static_cast<std::size_t>(k)]; }
  // Heights of frames 0..n with driven frame m (the frames above it locked rigid with it).
  void get_frame_heights(int m, double* y) const;
  double get_speed_m_per_s(int k) const { return v_[static_cast<std::size_t>(k)]; }

 private:
  model::ActiveFrames make_active(const StageSpec& s, int lo) const;
  const model::MastParams& mast_;
  std::vector<double> y_, v_;  // frames 0..n (frames above the driven one: not used)
  double x_ = 0, xi_ = 0;      // hinge offset of the deploying bay on the rail and its rate
};

}  // namespace truss::stages
