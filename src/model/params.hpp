// Parameters of one mast, bay by bay and frame by frame (MODEL.md section 1).
// Plain data; the model functions in this folder are pure functions of these and of the state.
#pragma once
#include <cmath>
#include <vector>

namespace truss::model {

// Bay i joins frame i-1 (below) and frame i (above); three longerons, each two struts.
struct BayParams {
  double strut_length_m = 0.18;             // l_s of both struts of this bay
  double strut_mass_kg = 0.1;               // m_s of one strut
  double strut_inertia_kg_m2 = 0.1 * 0.18 * 0.18 / 12.0;  // J_c, centroidal
  double diagonal_stiffness_N_per_m = 20.0; // K of one of the six diagonals
  double diagonal_free_length_m = 0.45;     // l_0 of one diagonal
};

// Frame k = 0..n: an equilateral triangle moving along the mast axis.
struct FrameParams {
  double side_m = 0.36;   // b_f
  double mass_kg = 0.5;   // m_f
};

struct RailParams {
  double x_m = 0.08;                      // x_l
  double y_m = 0.15;                      // y_l
  double beta_rad = 20.85 * M_PI / 180.0; // inclination to the mast axis
  double cot_beta() const { return 1.0 / std::tan(beta_rad); }
  // y_r: height at which the rail line crosses the longeron line (x = 0); the lock height of
  // the hinge.
  double axis_height_m() const { return y_m + x_m * cot_beta(); }
};

struct PanelParams {
  int count = 0;             // n_p (even); 0 = no panels, and no panel terms are computed
  double length_m = 0.5;     // l_p
  double mass_kg = 0.2;      // m_p of one panel
  double tip_height_m = 0.36;  // h_tip: blanket attachment above the top locked frame
  bool enabled() const { return count > 0; }
};

struct MastParams {
  std::vector<BayParams> bays;      // bays[i-1] is bay i, i = 1..n
  std::vector<FrameParams> frames;  // frames[k], k = 0..n
  double tip_mass_kg = 1.1;         // tip fitting moving with the top frame
  RailParams rail;
  PanelParams panels;

  int n_bays() const { return static_cast<int>(bays.size()); }
  const BayParams& bay(int i) const { return bays[static_cast<std::size_t>(i - 1)]; }
  const FrameParams& frame(int k) const { return frames[static_cast<std::size_t>(k)]; }
};

}  // namespace truss::model
