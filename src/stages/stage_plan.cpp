#include "stages/stage_plan.hpp"

#include <fmt/format.h>

#include "model/bay.hpp"
#include "model/rail.hpp"

namespace truss::stages {

using namespace truss::model;

namespace {

// Locked mass and blanket height offset above frame m, built from the top down: O(n).
void calc_rigid_above(const MastParams& mast, std::vector<double>& locked, std::vector<double>& span) {
  const int n = mast.n_bays();
  locked.assign(static_cast<std::size_t>(n + 1), 0.0);
  span.assign(static_cast<std::size_t>(n + 1), 0.0);
  locked[n] = mast.tip_mass_kg;
  span[n] = mast.panels.tip_height_m;
  for (int m = n - 1; m >= 1; --m) {
    locked[m] = locked[m + 1] + calc_rigid_bay_mass_kg(mast.bay(m + 1), mast.frame(m + 1));
    span[m] = span[m + 1] + 2.0 * mast.bay(m + 1).strut_length_m;
  }
}

}  // namespace

std::string plan_free_stages(const MastParams& mast, double direction, std::vector<StageSpec>& out) {
  out.clear();
  if (direction < 0) return "run.direction: retraction of a free stack (stack.mode = \"free\") is not available yet";
  const int n = mast.n_bays();
  std::vector<double> locked, span;
  calc_rigid_above(mast, locked, span);
  for (int m = n; m >= 1; --m) {
    StageSpec s;
    s.bay = m;
    s.start = (m == n) ? StageStart::from_rest_or_kick : StageStart::continue_motion;
    s.locked_mass_kg = locked[m];
    s.panel_height_offset_m = span[m];
    s.free_stack = true;
    s.phases.push_back({PhaseKind::open, 0.0, 0.0, PhaseEnd::rail_entry, 0.0});
    s.phases.push_back({PhaseKind::on_rail, 0.0, 0.0, PhaseEnd::lock, 0.0});
    out.push_back(s);
  }
  return {};
}

std::string plan_held_stages(const MastParams& mast, double direction, std::vector<StageSpec>& out) {
  const int n = mast.n_bays();
  out.clear();
  out.reserve(static_cast<std::size_t>(n));
  const double yr = mast.rail.axis_height_m();
  std::vector<double> locked, span;
  calc_rigid_above(mast, locked, span);
  std::vector<StageSpec> deploy(n);
  for (int m = n; m >= 1; --m) {
    const BayParams& b = mast.bay(m);
    const HeldRailEntry e = calc_held_rail_entry(mast.rail, b.strut_length_m, 0.0);
    if (!e.reachable)
      return fmt::format("rail: the held lower frame of bay {} never meets the rail (need c l_s > y_r - 0 > l_s with "
                         "c = cot(beta) = {:.6g}, l_s = {:.6g} m, y_r = y_l + c x_l = {:.6g} m)",
                         m, mast.rail.cot_beta(), b.strut_length_m, yr);
    const double y_start = (m == n) ? 0.0 : calc_lock_lower_height_m(mast.rail, mast.bay(m + 1).strut_length_m);
    if (!(y_start < e.upper_height_m))
      return fmt::format("rail: bay {} starts already past its rail entry (frame {} starts at {:.6g} m, entry at "
                         "{:.6g} m): the previous lock lifts it too high",
                         m, m, y_start, e.upper_height_m);
    StageSpec s;
    s.bay = m;
    s.direction = 1.0;
    s.start = (m == n) ? StageStart::from_rest_or_kick : StageStart::continue_motion;
    s.locked_mass_kg = locked[m];
    s.panel_height_offset_m = span[m];
    s.entry_hinge_x_m = e.hinge_x_m;
    s.entry_upper_height_m = e.upper_height_m;
    s.phases.push_back({PhaseKind::open, y_start, e.upper_height_m, PhaseEnd::rail_entry, 0.0});
    s.phases.push_back({PhaseKind::on_rail, e.hinge_x_m, 0.0, PhaseEnd::lock, 0.0});
    deploy[static_cast<std::size_t>(n - m)] = s;
  }
  if (direction > 0) {
    out = std::move(deploy);
    return {};
  }
  // Retraction: bays 1..n, each stage the reverse of its deployment stage.
  for (int idx = n - 1; idx >= 0; --idx) {
    const StageSpec& d = deploy[static_cast<std::size_t>(idx)];
    StageSpec s = d;
    s.direction = -1.0;
    s.start = StageStart::unlock;
    s.phases.clear();
    s.phases.push_back({PhaseKind::on_rail, 0.0, d.entry_hinge_x_m, PhaseEnd::rail_exit, 0.0});
    s.phases.push_back({PhaseKind::open, d.entry_upper_height_m, d.phases[0].q_start, PhaseEnd::reach_height, 0.0});
    s.final_landing = (d.bay == n);
    out.push_back(s);
  }
  return {};
}

}  // namespace truss::stages
