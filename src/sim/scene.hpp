// Scene options: what a user writes in a scene TOML file, parsed once into plain structs.
// Every field has a default (the paper's Table 1, MODEL.md section 4, or a project default named
// as such) and a one-line reason. validate() names the first bad field.
#pragma once
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "model/params.hpp"

namespace truss::sim {

enum class DriveMode { velocity, torque, motor };
enum class StackMode { held, free };
enum class Direction { deploy, retract };
enum class IntegratorKind { dopri54, cvode };

const char* to_string(DriveMode);
const char* to_string(StackMode);
const char* to_string(Direction);
const char* to_string(IntegratorKind);

struct MastOptions {
  int n_bays = 30;                               // Table 1: 30 bays
  double strut_length_m = 0.18;                  // Table 1: l_s
  double strut_mass_kg = 0.1;                    // Table 1: m_s
  std::optional<double> strut_inertia_kg_m2;     // J_c; unset = m_s l_s^2/12 (slender rod, MODEL.md 4)
  double frame_side_m = 0.36;                    // Table 1: b_f
  double frame_mass_kg = 0.5;                    // Table 1: m_f
  double diagonal_stiffness_N_per_m = 20.0;      // Table 1: K
  double diagonal_free_length_m = 0.45;          // Table 1: l_0
  std::optional<double> tip_mass_kg;             // unset = 6 m_s + m_f (reproduces paper eq. 3)
};

struct RailOptions {
  double x_m = 0.08;        // Table 1: x_l, rail foot offset from the longeron line
  double y_m = 0.15;        // Table 1: y_l, rail foot height
  double beta_deg = 20.85;  // Table 1: rail inclination to the mast axis
};

struct DriveOptions {
  DriveMode mode = DriveMode::velocity;   // the paper's constant-speed drive
  double speed_m_per_s = 0.1;             // Table 1: v_dep (velocity mode)
  double screw_lead_m = 0.01;             // project default h (paper leaves it open)
  double torque_Nm = 0.01;                // project default: 6.3 N of screw force, above the ~3 N spring peak
  double stall_torque_Nm = 0.02;          // project default motor: 12.6 N stall force
  double no_load_speed_rad_per_s = 75.0;  // project default: 0.119 m/s free-running screw speed
};

struct StackOptions {
  StackMode mode = StackMode::held;  // MODEL.md 2: the canister holds stowed frames
};

struct PanelOptions {
  int count = 0;                            // 0 = no solar blanket (Table 1 has none); else even
  double length_m = 0.5;                    // project default panel length l_p (used if count > 0)
  double mass_kg = 0.2;                     // project default panel mass m_p (used if count > 0)
  std::optional<double> tip_height_m;       // h_tip; unset = 2 l_s (the paper's 2(j+1) l_s)
};

struct RunOptions {
  Direction direction = Direction::deploy;  // deploy from the stowed stack, or retract into it
  double output_step_s = 0.0;               // time-history sample step; 0 = no histories (fastest)
  double rtol = 1e-8;                       // relative tolerance of the ODE integrators
  double atol = 1e-10;                      // absolute tolerance (m, m/s, J) of the ODE integrators
  IntegratorKind integrator = IntegratorKind::dopri54;  // own DP5(4) pair; cvode = SUNDIALS Adams
  long max_steps = 2'000'000;               // step cap over the whole run: a run never hangs
  double max_wall_time_s = 600.0;           // wall-time cap for one run
};

struct SceneOptions {
  MastOptions mast;
  RailOptions rail;
  DriveOptions drive;
  StackOptions stack;
  PanelOptions panels;
  RunOptions run;

  // Returns an empty string when valid, else "key: reason" naming the first bad key
  // (e.g. "rail.beta_deg: must lie in (0, 90) degrees, got 95").
  std::string validate() const;
};

// The per-bay / per-frame parameter set the model sees. Campaigns disperse its vectors.
model::MastParams build_mast(const SceneOptions& scene);

// Geometric checks on a (possibly dispersed) mast that the held stack needs: the rail is met by
// every held lower frame, the next bay starts outside the rail, panels stay folded.
// Empty string when valid, else "key: reason".
std::string validate_mast(const model::MastParams& mast, const SceneOptions& scene);

}  // namespace truss::sim
