// The scene of a Simbody cross-check run: the mast, rail and drive keys of a truss-sim scene file
// (campaigns/scenes/*.toml, keys as in docs/model.md §1-§2), read here with toml++ and nothing of
// truss-sim's code, so that the check stays independent. Keys this model cannot represent (a solar
// blanket, stack contacts, retraction, per-bay arrays) are refused, not ignored.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

namespace mastcheck {

// Bad input: what() is the complete message ("error: FILE: key: why").
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class DriveMode { velocity, torque, motor };

struct MastScene {
  int n_bays = 30;
  double strut_length_m = 0.18;           // l_s, one of the two struts of a longeron
  double strut_mass_kg = 0.1;             // m_s
  double strut_inertia_kg_m2 = -1;        // J_c about the centroid; < 0: m_s l_s^2 / 12
  double frame_side_m = 0.36;             // b_f
  double frame_mass_kg = 0.5;             // m_f
  double diagonal_stiffness_N_per_m = 20; // K of one diagonal
  double diagonal_free_length_m = 0.45;   // l_0
  double tip_mass_kg = -1;                // < 0: 6 m_s + m_f
  double rail_x_m = 0.08, rail_y_m = 0.15, rail_beta_deg = 20.85;
  DriveMode drive = DriveMode::velocity;
  double speed_m_per_s = 0.1, screw_lead_m = 0.01, torque_Nm = 0.01;
  double stall_torque_Nm = 0.02, no_load_speed_rad_per_s = 75;
  bool free_stack = false;  // stack.mode = "free": frames below the driven one move freely
  double rtol = 1e-8;       // run.rtol, used as Simbody's integration accuracy

  double calcStrutInertia() const {
    return strut_inertia_kg_m2 >= 0 ? strut_inertia_kg_m2 : strut_mass_kg * strut_length_m * strut_length_m / 12;
  }
  double calcTipMass() const { return tip_mass_kg >= 0 ? tip_mass_kg : 6 * strut_mass_kg + frame_mass_kg; }
};

// Reads `path`, then applies each override "table.key=value" (the value is TOML; a bare word is a
// string), as truss-sim's --set does. Throws SceneError.
MastScene read_scene(const std::string& path, const std::vector<std::string>& overrides);

}  // namespace mastcheck
