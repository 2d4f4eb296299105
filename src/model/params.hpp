// Parameters of one mast, bay by bay and frame by frame (docs/model.md §1).
// Plain data; the model functions in this folder are pure functions of these and of the state.
#pragma once
#include <cmath>
#include <vector>

namespace truss::model {

// The one place for the paper's Table 1 (docs/model.md §4) and the project's derived defaults; the
// scene options (sim/scene.hpp) and the parameter structs below read them from here.
namespace table1 {
inline constexpr int n_bays = 30;
inline constexpr double strut_length_m = 0.18;            // l_s
inline constexpr double strut_mass_kg = 0.1;              // m_s
inline constexpr double frame_side_m = 0.36;              // b_f
inline constexpr double frame_mass_kg = 0.5;              // m_f
inline constexpr double diagonal_stiffness_N_per_m = 20.0;  // K
inline constexpr double diagonal_free_length_m = 0.45;    // l_0
inline constexpr double rail_x_m = 0.08;                  // x_l
inline constexpr double rail_y_m = 0.15;                  // y_l
inline constexpr double rail_beta_deg = 20.85;            // beta
}  // namespace table1

// Derived defaults (docs/model.md §1 and 4; project defaults named as such there).
// J_c of a slender rod: m_s l_s^2 / 12.
constexpr double calc_default_strut_inertia_kg_m2(double strut_mass_kg, double strut_length_m) {
  return strut_mass_kg * strut_length_m * strut_length_m / 12.0;
}
// Tip fitting 6 m_s + m_f: reproduces the paper's (j+1) term in eq. 3.
constexpr double calc_default_tip_mass_kg(double strut_mass_kg, double frame_mass_kg) {
  return 6.0 * strut_mass_kg + frame_mass_kg;
}
// Blanket attachment 2 l_s above the top locked frame: the paper's 2(j+1) l_s.
constexpr double calc_default_tip_height_m(double strut_length_m) { return 2.0 * strut_length_m; }

// Bay i joins frame i-1 (below) and frame i (above); three longerons, each two struts.
struct BayParams {
  double strut_length_m = table1::strut_length_m;  // l_s of both struts of this bay
  double strut_mass_kg = table1::strut_mass_kg;    // m_s of one strut
  double strut_inertia_kg_m2 = calc_default_strut_inertia_kg_m2(table1::strut_mass_kg, table1::strut_length_m);  // J_c
  double diagonal_stiffness_N_per_m = table1::diagonal_stiffness_N_per_m;  // K of one of the six diagonals
  double diagonal_free_length_m = table1::diagonal_free_length_m;          // l_0 of one diagonal
};

// Frame k = 0..n: an equilateral triangle moving along the mast axis.
struct FrameParams {
  double side_m = table1::frame_side_m;    // b_f
  double mass_kg = table1::frame_mass_kg;  // m_f
};

struct RailParams {
  double x_m = table1::rail_x_m;                         // x_l
  double y_m = table1::rail_y_m;                         // y_l
  double beta_rad = table1::rail_beta_deg * M_PI / 180.0; // inclination to the mast axis
  double cot_beta() const { return 1.0 / std::tan(beta_rad); }
  // y_r: height at which the rail line crosses the longeron line (x = 0); the lock height of
  // the hinge.
  double axis_height_m() const { return y_m + x_m * cot_beta(); }
};

struct PanelParams {
  int count = 0;             // n_p (even); 0 = no panels, and no panel terms are computed
  double length_m = 0.5;     // l_p
  double mass_kg = 0.2;      // m_p of one panel
  double tip_height_m = calc_default_tip_height_m(table1::strut_length_m);  // h_tip above the top locked frame
  bool enabled() const { return count > 0; }
};

struct MastParams {
  std::vector<BayParams> bays;      // bays[i-1] is bay i, i = 1..n
  std::vector<FrameParams> frames;  // frames[k], k = 0..n
  double tip_mass_kg = calc_default_tip_mass_kg(table1::strut_mass_kg, table1::frame_mass_kg);  // moves with the top frame
  RailParams rail;
  PanelParams panels;

  int n_bays() const { return static_cast<int>(bays.size()); }
  const BayParams& bay(int i) const { return bays[static_cast<std::size_t>(i - 1)]; }
  const FrameParams& frame(int k) const { return frames[static_cast<std::size_t>(k)]; }
};

}  // namespace truss::model
