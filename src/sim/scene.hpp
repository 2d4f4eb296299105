// Scene options: what a user writes in a scene TOML file, parsed once into plain structs.
// Every field has a default (the paper's Table 1, docs/model.md §4, or a project default named
// as such) and a one-line reason. validate() names the first bad field.
#pragma once
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "integrators/ode.hpp"
#include "model/drive.hpp"
#include "model/motorisation.hpp"
#include "model/params.hpp"
#include "stages/run_options.hpp"
#include "stages/stage_plan.hpp"

namespace truss::sim {

using model::Direction;
using model::DriveMode;
using integrators::IntegratorKind;
enum class StackMode { held, free };
enum class StackContacts { off, on };   // TOML false | true
enum class ContactLaw { plastic };
enum class StackStart { kick, rest };   // the free frames at the velocity drive's impulsive start

using model::to_string;
using integrators::to_string;
const char* to_string(StackMode);

struct MastOptions {
  int n_bays = model::table1::n_bays;                          // Table 1: 30 bays
  double strut_length_m = model::table1::strut_length_m;      // Table 1: l_s
  double strut_mass_kg = model::table1::strut_mass_kg;        // Table 1: m_s
  std::optional<double> strut_inertia_kg_m2;  // J_c; unset = model::calc_default_strut_inertia_kg_m2
  double frame_side_m = model::table1::frame_side_m;          // Table 1: b_f
  double frame_mass_kg = model::table1::frame_mass_kg;        // Table 1: m_f
  double diagonal_stiffness_N_per_m = model::table1::diagonal_stiffness_N_per_m;  // Table 1: K
  double diagonal_free_length_m = model::table1::diagonal_free_length_m;          // Table 1: l_0
  std::optional<double> tip_mass_kg;          // unset = model::calc_default_tip_mass_kg (paper eq. 3)
  // Resolved defaults (docs/model.md §1, 4), the one place the optional keys are filled in.
  double calc_strut_inertia_kg_m2() const {
    return strut_inertia_kg_m2.value_or(model::calc_default_strut_inertia_kg_m2(strut_mass_kg, strut_length_m));
  }
  double calc_tip_mass_kg() const {
    return tip_mass_kg.value_or(model::calc_default_tip_mass_kg(strut_mass_kg, frame_mass_kg));
  }
};

struct RailOptions {
  double x_m = model::table1::rail_x_m;             // Table 1: x_l, rail foot offset from the longeron line
  double y_m = model::table1::rail_y_m;             // Table 1: y_l, rail foot height
  double beta_deg = model::table1::rail_beta_deg;   // Table 1: rail inclination to the mast axis
};

// The drive options are the model's drive parameters (model/drive.hpp): one type, one default.
using DriveOptions = model::DriveParams;
// The motorisation check's factors (model/motorisation.hpp, ECSS-E-ST-33-01C 4.7.5.3.1).
using MotorisationOptions = model::MotorisationFactors;

struct StackOptions {
  StackMode mode = StackMode::held;  // docs/model.md §2: the canister holds stowed frames
  StackContacts contacts = StackContacts::off;  // docs/model.md §2 "free": contacts optional; off = the paper's literal model
  ContactLaw contact_law = ContactLaw::plastic;  // docs/model.md §2: plastic by default (the only law so far)
  // Free stack, velocity drive, deployment: the free frames take the momentum-consistent kick of
  // the impulsive start (kick), or stay at rest while the driven frame jumps to v (rest, the
  // paper's literal start). docs/model-notes.md, "Start".
  StackStart start = StackStart::kick;
};

struct PanelOptions {
  int count = 0;                            // 0 = no solar blanket (Table 1 has none); else even
  double length_m = 0.5;                    // project default panel length l_p (used if count > 0)
  double mass_kg = 0.2;                     // project default panel mass m_p (used if count > 0)
  std::optional<double> tip_height_m;       // h_tip; unset = model::calc_default_tip_height_m
  double calc_tip_height_m(double strut_length_m) const {
    return tip_height_m.value_or(model::calc_default_tip_height_m(strut_length_m));
  }
};

// The [run] table is the stage loop's run options (stages/run_options.hpp): one type, one default.
using RunOptions = stages::RunOptions;

struct SceneOptions {
  MastOptions mast;
  RailOptions rail;
  DriveOptions drive;
  StackOptions stack;
  PanelOptions panels;
  RunOptions run;
  MotorisationOptions motorisation;

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
// Its parts: per-bay and per-frame parameters positive; the blanket longer than the mast.
std::string validate_mast_params(const model::MastParams& mast);
// The stage plan of the scene's stack mode (stages/stage_plan.hpp): "" or "key: reason".
std::string plan_stages(const SceneOptions& scene, const model::MastParams& mast, double direction,
                        std::vector<stages::StageSpec>& out);
std::string validate_panels(const model::MastParams& mast);

}  // namespace truss::sim
