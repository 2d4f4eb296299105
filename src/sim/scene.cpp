#include "sim/scene.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "model/bay.hpp"
#include "sim/scene_keys.hpp"
#include "stages/history.hpp"
#include "stages/stage_plan.hpp"

namespace truss::sim {

const char* to_string(StackMode m) { return m == StackMode::held ? "held" : "free"; }

namespace {
std::string positive(const char* key, double v) {
  if (!(std::isfinite(v) && v > 0.0)) return fmt::format("{}: must be a positive number, got {}", key, v);
  return {};
}
std::string finite(const char* key, double v) {
  if (!std::isfinite(v)) return fmt::format("{}: must be a finite number, got {}", key, v);
  return {};
}
}  // namespace

std::string SceneOptions::validate() const {
  std::string e;
#define CHECK(expr) if (!(e = (expr)).empty()) return e
  if (mast.n_bays < 1 || mast.n_bays > 100000)
    return fmt::format("mast.n_bays: must lie in [1, 100000], got {}", mast.n_bays);
  CHECK(positive("mast.strut_length_m", mast.strut_length_m));
  CHECK(positive("mast.strut_mass_kg", mast.strut_mass_kg));
  if (mast.strut_inertia_kg_m2) CHECK(positive("mast.strut_inertia_kg_m2", *mast.strut_inertia_kg_m2));
  CHECK(positive("mast.frame_side_m", mast.frame_side_m));
  CHECK(positive("mast.frame_mass_kg", mast.frame_mass_kg));
  CHECK(positive("mast.diagonal_stiffness_N_per_m", mast.diagonal_stiffness_N_per_m));
  CHECK(positive("mast.diagonal_free_length_m", mast.diagonal_free_length_m));
  if (mast.tip_mass_kg && !(std::isfinite(*mast.tip_mass_kg) && *mast.tip_mass_kg >= 0.0))
    return fmt::format("mast.tip_mass_kg: must be a finite number >= 0, got {}", *mast.tip_mass_kg);
  CHECK(finite("rail.x_m", rail.x_m));
  CHECK(finite("rail.y_m", rail.y_m));
  if (!(rail.beta_deg > 0.0 && rail.beta_deg < 90.0))
    return fmt::format("rail.beta_deg: must lie in (0, 90) degrees, got {}", rail.beta_deg);
  // The model reads the rail through cot(beta): a beta whose cotangent overflows (below about
  // 1e-306 deg) is a rail parallel to the mast to double precision.
  if (const double beta_rad = rail.beta_deg * M_PI / 180.0; !std::isfinite(1.0 / std::tan(beta_rad)))
    return fmt::format("rail.beta_deg: {} deg is too small: its cotangent is not a finite double (the rail would be "
                       "parallel to the mast); give at least 1e-300 deg", rail.beta_deg);
  CHECK(positive("drive.speed_m_per_s", drive.speed_m_per_s));
  CHECK(positive("drive.screw_lead_m", drive.screw_lead_m));
  CHECK(positive("drive.torque_Nm", drive.torque_Nm));
  CHECK(positive("drive.stall_torque_Nm", drive.stall_torque_Nm));
  CHECK(positive("drive.no_load_speed_rad_per_s", drive.no_load_speed_rad_per_s));
  if (!(drive.screw_back_efficiency > 0.0))
    return fmt::format("drive.screw_back_efficiency: must lie in (0, 1], got {}: a self-locking lead screw "
                       "(tan(lambda - phi) <= 0) cannot be backdriven, and the drive train's law needs it to be "
                       "(docs/model-notes.md \"Drive train\")", drive.screw_back_efficiency);
  if (run.integrator == IntegratorKind::ida && stack.mode != StackMode::free)
    return "run.integrator: \"ida\" solves the free stack's phases only (stack.mode = \"free\"); the held stack "
           "has one coordinate per phase and no rail multiplier: use \"dopri54\", \"dop853\", \"cvode\", \"cvode_adams\" or \"auto\"";
  if (stack.contacts == StackContacts::on && stack.mode != StackMode::free)
    return "stack.contacts: contacts between stowed frames apply to the free stack only (stack.mode = \"free\"); the held stack's canister holds them";
  if (stack.start == StackStart::rest && stack.mode != StackMode::free)
    return "stack.start: \"rest\" applies to the free stack only (stack.mode = \"free\"); the held stack's canister holds the stowed frames at rest anyway";
  if (panels.count < 0 || panels.count % 2 != 0)
    return fmt::format("panels.count: must be 0 (no panels) or a positive even number, got {}", panels.count);
  if (panels.count > 0) {
    CHECK(positive("panels.length_m", panels.length_m));
    CHECK(positive("panels.mass_kg", panels.mass_kg));
    if (panels.tip_height_m) CHECK(positive("panels.tip_height_m", *panels.tip_height_m));
  }
  CHECK(run.validate());
  if (run.output_step_s > 0.0) {  // two rows at least (stages/history.hpp), the frame heights included
    const long row_B = stages::calc_history_row_bytes(stack.mode == StackMode::free ? mast.n_bays + 1 : 0);
    if (run.max_history_bytes < 2 * row_B)
      return fmt::format("run.max_history_bytes: {} B holds fewer than two history rows of {} B ({} bays, {} stack); "
                         "raise it or set run.output_step_s = 0", run.max_history_bytes, row_B, mast.n_bays,
                         stack.mode == StackMode::free ? "free" : "held");
  }
  // Magnitudes: every numeric key against its hard range (sim/scene_keys.hpp), so that 1e308
  // never reaches the physics.
  CHECK(check_scene_ranges(*this));
#undef CHECK
  return {};
}

std::string plan_stages(const SceneOptions& scene, const model::MastParams& mast, double direction,
                        std::vector<stages::StageSpec>& out) {
  if (scene.stack.mode == StackMode::free)
    return stages::plan_free_stages(mast, direction, scene.stack.contacts == StackContacts::on,
                                    scene.stack.start == StackStart::kick, out);
  return stages::plan_held_stages(mast, direction, out);
}

model::MastParams build_mast(const SceneOptions& s) {
  model::MastParams m;
  const auto& o = s.mast;
  const int n = std::max(o.n_bays, 0);
  model::BayParams b;
  b.strut_length_m = o.strut_length_m;
  b.strut_mass_kg = o.strut_mass_kg;
  b.strut_inertia_kg_m2 = o.calc_strut_inertia_kg_m2();
  b.diagonal_stiffness_N_per_m = o.diagonal_stiffness_N_per_m;
  b.diagonal_free_length_m = o.diagonal_free_length_m;
  m.bays.assign(static_cast<std::size_t>(n), b);
  m.frames.assign(static_cast<std::size_t>(n + 1), model::FrameParams{o.frame_side_m, o.frame_mass_kg});
  m.tip_mass_kg = o.calc_tip_mass_kg();
  m.rail.x_m = s.rail.x_m;
  m.rail.y_m = s.rail.y_m;
  m.rail.beta_rad = s.rail.beta_deg * M_PI / 180.0;
  m.panels.count = s.panels.count;
  m.panels.length_m = s.panels.length_m;
  m.panels.mass_kg = s.panels.mass_kg;
  m.panels.tip_height_m = s.panels.calc_tip_height_m(o.strut_length_m);
  return m;
}

std::string validate_mast_params(const model::MastParams& mast) {
  const int n = mast.n_bays();
  if (n < 1 || static_cast<int>(mast.frames.size()) != n + 1) return "mast.n_bays: inconsistent bay and frame counts";
  for (int i = 1; i <= n; ++i) {
    const auto& b = mast.bay(i);
    if (!(b.strut_length_m > 0.0)) return fmt::format("mast.strut_length_m: bay {} has a non-positive strut length {}", i, b.strut_length_m);
    if (!(b.strut_mass_kg > 0.0)) return fmt::format("mast.strut_mass_kg: bay {} has a non-positive strut mass {}", i, b.strut_mass_kg);
    if (!(b.strut_inertia_kg_m2 > 0.0)) return fmt::format("mast.strut_inertia_kg_m2: bay {} has a non-positive inertia {}", i, b.strut_inertia_kg_m2);
    if (!(b.diagonal_stiffness_N_per_m > 0.0)) return fmt::format("mast.diagonal_stiffness_N_per_m: bay {} has {}", i, b.diagonal_stiffness_N_per_m);
    if (!(b.diagonal_free_length_m > 0.0)) return fmt::format("mast.diagonal_free_length_m: bay {} has {}", i, b.diagonal_free_length_m);
  }
  for (int k = 0; k <= n; ++k) {
    if (!(mast.frame(k).side_m > 0.0)) return fmt::format("mast.frame_side_m: frame {} has {}", k, mast.frame(k).side_m);
    if (!(mast.frame(k).mass_kg > 0.0)) return fmt::format("mast.frame_mass_kg: frame {} has {}", k, mast.frame(k).mass_kg);
  }
  return check_mast_ranges(mast);  // dispersed per-bay and per-frame values: the keys' hard ranges
}

std::string validate_panels(const model::MastParams& mast) {
  if (!mast.panels.enabled()) return {};
  // H is largest with the mast fully deployed: y_0 = y_r - l_1 plus every bay and the tip.
  const int n = mast.n_bays();
  double H = mast.rail.axis_height_m() - mast.bay(1).strut_length_m + mast.panels.tip_height_m;
  for (int i = 1; i <= n; ++i) H += 2.0 * mast.bay(i).strut_length_m;
  const double reach = mast.panels.count * mast.panels.length_m;
  if (!(H < reach))
    return fmt::format("panels.length_m: the blanket ({} panels x {} m = {} m) must stay longer than the mast "
                       "height H, which reaches {:.6g} m (docs/model.md §1: H < n_p l_p)",
                       mast.panels.count, mast.panels.length_m, reach, H);
  return {};
}

std::string validate_mast(const model::MastParams& mast, const SceneOptions& scene) {
  std::string e = validate_mast_params(mast);
  std::vector<stages::StageSpec> plan;
  if (e.empty()) e = plan_stages(scene, mast, 1.0, plan);
  if (e.empty()) e = validate_panels(mast);
  return e;
}

}  // namespace truss::sim
