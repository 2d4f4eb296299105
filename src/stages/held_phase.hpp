// One phase of a held-stack stage, as a 1-DOF system in a regular coordinate q:
//   open    (hinge off the rail, MODEL.md 2 phase A): q = y_m, lower frame held at rest;
//   on_rail (phase B): q = x, the hinge offset of bay m, with y_m = Y(x), y_{m-1} = Z(x)
//            (rail.hpp) and frame m-2 held: regular at the lock x = 0 (MODEL.md 3, trap).
// On the rail the frame-height equations (model/frames.hpp) are mapped to coordinates (y_m, x):
//   dy_{m-1}/dt = u + k xi,  k = 2x/s,  d2y_{m-1}/dt2 = du/dt + k dxi/dt + k' xi^2,  k' = 2 l^2/s^3,
//   M_yy = A_mm + 2 A_ml + A_ll,  M_yx = k (A_ml + A_ll),  M_xx = k^2 A_ll + 2 g(x),
//   R_y = r_m + r_l + Q_m + Q_l - (A_ml + A_ll) k' xi^2 + F,
//   R_x = k (r_l + Q_l - A_ll k' xi^2) - g'(x) xi^2,
//   M_yy y_m'' + M_yx x'' = R_y + lambda,   M_yx y_m'' + M_xx x'' = R_x + lambda (c + x/s),
// with the rail y_m'' = Y' x'' + Y'' xi^2, Y' = -(c + x/s) = -gamma. Eliminating lambda:
//   mu x'' = R_x - gamma R_y - (M_yx - gamma M_yy) Y'' xi^2,  mu = M_xx - 2 gamma M_yx + gamma^2 M_yy.
// Velocity mode prescribes y_m'' = 0, so x'' = Y'' xi^2 / gamma and the two rows give lambda and the
// drive force F (inverse dynamics). Every term is regular at x = 0.
#pragma once
#include <vector>

#include "model/frames.hpp"
#include "model/params.hpp"
#include "model/rail.hpp"

namespace truss::stages {

enum class PhaseKind { open, on_rail };
enum class DriveLaw { velocity, torque, motor };

struct DriveParams {
  DriveLaw law = DriveLaw::velocity;
  double direction = 1.0;             // +1 deploy (driven frame up), -1 retract
  double speed_m_per_s = 0.1;         // velocity mode
  double screw_lead_m = 0.01;
  double torque_Nm = 0.01;            // torque mode, along the run direction
  double stall_torque_Nm = 0.02;      // motor mode
  double no_load_speed_rad_per_s = 75.0;
  // Screw force (N, along +y) for a driven-frame velocity u (torque and motor modes).
  double calc_force_N(double u) const;
  double calc_torque_Nm(double force_N) const;  // M = F h / (2 pi)
};

// Everything a phase needs, fixed for the phase.
struct PhaseContext {
  const model::MastParams* mast = nullptr;
  PhaseKind kind = PhaseKind::open;
  int bay = 0;                        // deploying bay m; driven frame m, lower frame m-1
  double lower_held_height_m = 0;     // open: height of frame m-1 (held); on_rail: of frame m-2
  double locked_mass_kg = 0;          // locked bays above m + tip
  double panel_height_offset_m = 0;   // H = y_m + offset
  DriveParams drive;
};

// Everything one evaluation of a phase gives: state in frame heights, accelerations, loads.
struct PhasePoint {
  double q = 0, qdot = 0, qddot = 0;  // phase coordinate (y_m or x) and its derivatives
  double y_driven_m = 0, y_lower_m = 0;
  double u_m_per_s = 0, w_m_per_s = 0;  // velocities of driven and lower frame
  double hinge_x_m = 0, hinge_y_m = 0;
  double drive_force_N = 0;
  double lambda_N = 0;                // rail multiplier (0 off the rail)
  double pin_force_N = 0;
  double diagonal_tension_N = 0;      // largest tension of one diagonal in the moving bays
  double kinetic_energy_J = 0;
  double potential_energy_J = 0;      // diagonals of the moving bays (m and, on the rail, m-1)
  double rail_residual_m = 0;
  // Mass matrix in the phase's coordinates: open: mass_yy only; on_rail: (y_m, x) entries.
  double mass_yy = 0, mass_yx = 0, mass_xx = 0;
  double rail_slope = 0;              // on_rail: gamma = c + x/s = df/dx = -Y'(x)
};

// Evaluates the phase at (q, qdot). In velocity mode qdot must be the prescribed kinematics
// (y_m' = direction * v) and q'' is computed from it; otherwise the drive law gives F.
class HeldPhase {
 public:
  explicit HeldPhase(const PhaseContext& ctx);
  PhasePoint calc_point(double q, double qdot) const;
  const PhaseContext& context() const { return ctx_; }
  double strut_length_m() const { return ctx_.mast->bay(ctx_.bay).strut_length_m; }

 private:
  PhasePoint calc_open(double y, double u) const;
  PhasePoint calc_on_rail(double x, double xi) const;
  PhaseContext ctx_;
  model::ActiveFrames active_;
  mutable model::FrameSystem sys_;
  mutable double y_[3] = {0, 0, 0};   // frames m-2, m-1, m (local scratch)
  mutable double v_[3] = {0, 0, 0};
  double b2_m_ = 0, b2_lower_ = 0;    // diagonal offsets^2 of bays m and m-1
};

}  // namespace truss::stages
