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

// A held lower frame at z0 = 0 must meet the rail away from the straight and the closed bay
// (model/rail.hpp, calc_held_entry_range); otherwise the run is refused, naming the keys, the
// reason and the valid range of rail.x_m for the other keys' values.
std::string check_held_entry(const MastParams& mast, int m, const HeldRailEntry& e) {
  const RailParams& r = mast.rail;
  const double l = mast.bay(m).strut_length_m, c = r.cot_beta(), h = r.axis_height_m();
  const double beta_deg = r.beta_rad * 180.0 / M_PI;
  const HeldEntryRange ok = calc_held_entry_range(r, l);
  if (e.reachable && h >= ok.h_min_m && h < ok.h_below_m) return {};
  const std::string where = fmt::format(
      "the rail's height on the mast axis y_r = rail.y_m + rail.x_m cot(rail.beta_deg) = {:.9g} m (rail.y_m = {:.9g} m, "
      "rail.x_m = {:.9g} m, rail.beta_deg = {:.9g} deg) against bay {}'s strut length mast.strut_length_m = {:.9g} m",
      h, r.y_m, r.x_m, beta_deg, m, l);
  if (!(ok.h_min_m < ok.h_below_m))
    return fmt::format("rail geometry: bay {}'s held lower frame never meets the rail properly: with rail.beta_deg = {:.9g} deg "
                       ">= 45 deg the rail rises at most as fast (cot beta = {:.6g} <= 1) as the hinge on its arc, so the "
                       "pin cannot meet the rail between the closed and the straight bay for any rail.x_m, rail.y_m; "
                       "choose rail.beta_deg below 45 deg ({})",
                       m, beta_deg, c, where);
  const double x_lo = (ok.h_min_m - r.y_m) / c, x_hi = (ok.h_below_m - r.y_m) / c;
  const char* why = h < ok.h_min_m
                        ? "the bay would straighten (to within 1e-4 l_s) before its pin meets the rail, a singular "
                          "configuration of the held stack (the struts' radial speed grows without bound)"
                        : "the stowed hinge is not clear of the rail (clearance c l_s - y_r <= 0): the rail passes "
                          "at or below the closed bay's pin and never takes it";
  return fmt::format("rail geometry: bay {}: {}. y_r must lie in [{:.9g}, {:.9g}) m, i.e. rail.x_m in [{:.9g}, {:.9g}) m for "
                     "these rail.y_m, rail.beta_deg and mast.strut_length_m; {}",
                     m, why, ok.h_min_m, ok.h_below_m, x_lo, x_hi, where);
}

// Frame m starts where the lock of bay m+1 left it, y_r - l_s(m+1); its bay's pin must still be
// below the rail then. The bound on rail.x_m is found by bisection: raising y_r raises the start
// and lowers the entry, so start - entry is increasing in x_l.
std::string explain_start_past_entry(const MastParams& mast, int m, double y_start, double y_entry) {
  const double l = mast.bay(m).strut_length_m, l_up = mast.bay(m + 1).strut_length_m;
  auto excess = [&](double x) {
    RailParams r = mast.rail;
    r.x_m = x;
    return (r.axis_height_m() - l_up) - calc_held_rail_entry(r, l, 0.0).upper_height_m;
  };
  const HeldEntryRange ok = calc_held_entry_range(mast.rail, l);
  const double c = mast.rail.cot_beta();
  double lo = (ok.h_min_m - mast.rail.y_m) / c, hi = mast.rail.x_m;
  for (int i = 0; i < 200 && excess(lo) < 0.0 && hi - lo > 1e-15 * std::abs(hi); ++i) {
    const double mid = 0.5 * (lo + hi);
    (excess(mid) < 0.0 ? lo : hi) = mid;
  }
  return fmt::format("rail geometry: bay {} starts already past its rail entry: the lock of bay {} lifts frame {} to "
                     "y_r - l_s({}) = {:.6g} m, above the height {:.6g} m at which bay {}'s pin meets the rail; with these "
                     "rail.y_m, rail.beta_deg and mast.strut_length_m (bays {} and {}), rail.x_m must be below {:.9g} m "
                     "(now {:.9g} m)",
                     m, m + 1, m, m + 1, y_start, y_entry, m, m, m + 1, lo, mast.rail.x_m);
}

}  // namespace

std::string find_rail_entries(const MastParams& mast, std::vector<HeldRailEntry>& entries) {
  const int n = mast.n_bays();
  entries.assign(static_cast<std::size_t>(n + 1), HeldRailEntry{});
  const double y_r = mast.rail.axis_height_m();
  HeldRailEntry e;
  for (int m = n; m >= 1; --m) {
    const BayParams& b = mast.bay(m);
    // The entry depends on the strut length alone (the rail is the mast's): computed again only
    // where the length changes (a dispersed mast), with its check.
    if (m == n || b.strut_length_m != mast.bay(m + 1).strut_length_m) {
      e = calc_held_rail_entry(mast.rail, b.strut_length_m, 0.0);
      if (std::string bad = check_held_entry(mast, m, e); !bad.empty()) return bad;
    }
    const double y_start = (m == n) ? 0.0 : y_r - mast.bay(m + 1).strut_length_m;  // calc_lock_lower_height_m
    if (!(y_start < e.upper_height_m)) return explain_start_past_entry(mast, m, y_start, e.upper_height_m);
    entries[static_cast<std::size_t>(m)] = e;
  }
  return {};
}

std::string plan_free_stages(const MastParams& mast, double direction, bool contacts, bool start_kick,
                             std::vector<StageSpec>& out) {
  out.clear();
  if (direction < 0) {
    // Retraction: the held stack's stages (unlock, on the rail until the pin leaves it where a
    // lower frame at the stowed height meets it, then down to the deployment's start height),
    // with the frames below moving (free_stack/free_stack.hpp).
    if (std::string bad = plan_held_stages(mast, direction, out); !bad.empty()) return bad;
    for (StageSpec& s : out) { s.free_stack = true; s.contacts = contacts; }
    return {};
  }
  // The held stack's rail geometry: frame 0 is held on the floor until bay 1's rail takes it, as
  // in the held stack, and the stack starts stowed, so a geometry that the held stack refuses
  // fails the free stack as well (bay 1 would start past its rail entry, bay n's stowed pin would
  // not be clear of the rail, ...): refused with the same message.
  std::vector<HeldRailEntry> entries;
  if (std::string bad = find_rail_entries(mast, entries); !bad.empty()) return bad;
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
    s.contacts = contacts;
    s.start_kick = start_kick;
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
  std::vector<double> locked, span;
  calc_rigid_above(mast, locked, span);
  std::vector<StageSpec> deploy(n);
  std::vector<HeldRailEntry> entries;
  if (std::string bad = find_rail_entries(mast, entries); !bad.empty()) return bad;
  const double y_r = mast.rail.axis_height_m();
  for (int m = n; m >= 1; --m) {
    const HeldRailEntry& e = entries[static_cast<std::size_t>(m)];
    const double y_start = (m == n) ? 0.0 : y_r - mast.bay(m + 1).strut_length_m;  // calc_lock_lower_height_m
    StageSpec s;
    s.bay = m;
    s.direction = 1.0;
    s.start = (m == n) ? StageStart::from_rest_or_kick : StageStart::continue_motion;
    s.locked_mass_kg = locked[m];
    s.panel_height_offset_m = span[m];
    s.entry_hinge_x_m = e.hinge_x_m;
    s.entry_upper_height_m = e.upper_height_m;
    s.phases.reserve(2);
    s.phases.push_back({PhaseKind::open, y_start, e.upper_height_m, PhaseEnd::rail_entry, 0.0});
    s.phases.push_back({PhaseKind::on_rail, e.hinge_x_m, 0.0, PhaseEnd::lock, 0.0});
    deploy[static_cast<std::size_t>(n - m)] = std::move(s);
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
