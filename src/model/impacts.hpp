// Impact laws of a stage (docs/model.md §2): plastic impacts of the moving frames, each as a
// pure function of the pre-impact state. Notation: v = (w, u) the velocities of the lower frame
// m-1 and the driven frame m, M their 2x2 mass matrix in frame heights (model/frames.hpp, bay m
// with its G terms: regular away from the lock), J = grad f the rail row.
//
// Rail entry (held lower frame at rest meets the rail; impulse equations M dv = J^T Lambda):
//   torque / motor drives (the drive force is finite, no drive impulse):
//     Lambda = -(J v-) / (J M^-1 J^T),  dv = M^-1 J^T Lambda            (plastic: J v+ = 0)
//   velocity drive (the screw keeps u: du = 0, the drive takes an impulse P_d):
//     J_l (w + dw) + J_m u = 0,  Lambda = M_ll dw / J_l,  P_d = M_ml dw - J_m Lambda
//   with J = (1/2 + c D/(4x), 1/2 - c D/(4x)) (docs/model.md §3, misprint 4 corrected: df/dy_{m-1},
//   df/dy_m). Energy lost: (1/2) dv^T M dv (Carnot); drive impulse work P_d u.
// Latch (x -> 0): the struts' radial motion stops, (1/2) M_xx xi^2 = g(0) xi^2 is lost, y_m' is
//   continuous.
// Unlock (retraction start; coordinates (y_m, x) at x = 0, where M_yx = 0 and grad f = (1, c)):
//   velocity drive: the hinge must leave at the rail's speed xi = -u/c; the rail impulse
//     Lambda = M_xx xi / c is paid by the drive, P_d = -Lambda, work P_d u, lost P_d u - (1/2) M_xx xi^2;
//   torque / motor: plastic impact with the rail, Lambda = -u / (1/M_yy + c^2/M_xx),
//     du = Lambda / M_yy, xi = c Lambda / M_xx, lost (1/2)(M_yy du^2 + M_xx xi^2).
// Rail exit (retraction: the lower frame lands on the stack, w+ = 0): dw = -w;
//   velocity drive du = 0, P_d = M_ml dw; torque / motor du = -M_ml dw / M_mm;
//   stack impulse M_ll dw + M_ml du, lost (1/2) dv^T M dv.
// Start of the driven part from rest in velocity mode: a lossless drive ramp, impulse M u, work
//   (1/2) M u^2 (docs/model.md §4). Final landing of the stowed mast: all its kinetic energy is lost.
#pragma once
#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace truss::model {

// Mass matrix of frames (m-1, m) in frame heights: [[ll, ml], [ml, mm]].
struct TwoFrameMass {
  double ll = 0, ml = 0, mm = 0;
  Eigen::Matrix2d matrix() const { return (Eigen::Matrix2d() << ll, ml, ml, mm).finished(); }
};

struct FrameImpact {
  double dw_m_per_s = 0, du_m_per_s = 0;  // velocity jumps of the lower and the driven frame
  double rail_impulse_Ns = 0;             // Lambda, the rail multiplier's impulse (all three pins)
  double stack_impulse_Ns = 0;            // rail exit: impulse of the stack on the lower frame
  double drive_impulse_Ns = 0;            // velocity drive only
  double energy_loss_J = 0;               // (1/2) dv^T M dv
  double drive_work_J = 0;                // P_d u
};

inline double calc_impact_loss_J(const TwoFrameMass& M, double dw, double du) {
  return 0.5 * (M.ll * dw * dw + 2.0 * M.ml * dw * du + M.mm * du * du);
}

// J = (J_l, J_m) = (df/dy_{m-1}, df/dy_m) of a bay of opening D with its hinge at x on the rail.
inline Eigen::Vector2d calc_rail_gradient(double cot_beta, double D, double x) {
  return {0.5 + cot_beta * D / (4.0 * x), 0.5 - cot_beta * D / (4.0 * x)};
}

inline FrameImpact calc_rail_entry_impact(const TwoFrameMass& M, const Eigen::Vector2d& J, double u,
                                          bool drive_holds_speed) {
  const double Jl = J[0], Jm = J[1];
  FrameImpact r;
  if (drive_holds_speed) {
    r.dw_m_per_s = -Jm * u / Jl;
    r.rail_impulse_Ns = M.ll * r.dw_m_per_s / Jl;
    r.drive_impulse_Ns = M.ml * r.dw_m_per_s - Jm * r.rail_impulse_Ns;
  } else {
    const Eigen::Vector2d MinvJ = M.matrix().ldlt().solve(J);  // M > 0: LDL^T
    r.rail_impulse_Ns = -(Jm * u) / J.dot(MinvJ);
    r.dw_m_per_s = MinvJ[0] * r.rail_impulse_Ns;
    r.du_m_per_s = MinvJ[1] * r.rail_impulse_Ns;
  }
  r.energy_loss_J = calc_impact_loss_J(M, r.dw_m_per_s, r.du_m_per_s);
  r.drive_work_J = r.drive_impulse_Ns * u;
  return r;
}

inline FrameImpact calc_rail_exit_impact(const TwoFrameMass& M, double w, double u, bool drive_holds_speed) {
  FrameImpact r;
  r.dw_m_per_s = -w;
  if (drive_holds_speed) r.drive_impulse_Ns = M.ml * r.dw_m_per_s;
  else r.du_m_per_s = -M.ml * r.dw_m_per_s / M.mm;
  r.stack_impulse_Ns = M.ll * r.dw_m_per_s + M.ml * r.du_m_per_s;
  r.energy_loss_J = calc_impact_loss_J(M, r.dw_m_per_s, r.du_m_per_s);
  r.drive_work_J = r.drive_impulse_Ns * u;
  return r;
}

// Latch: energy lost when the hinge speed xi stops; M_xx = 2 g(0) at x = 0.
inline double calc_latch_loss_J(double mass_xx_kg, double hinge_speed_m_per_s) {
  return 0.5 * mass_xx_kg * hinge_speed_m_per_s * hinge_speed_m_per_s;
}

struct UnlockImpact {
  double du_m_per_s = 0;       // driven-frame velocity jump
  double hinge_speed_m_per_s = 0;  // xi after the unlock
  double rail_impulse_Ns = 0;  // Lambda, the rail's impulse (all three pins)
  double drive_work_J = 0;     // velocity drive: work of its impulse
  double energy_loss_J = 0;
};

inline UnlockImpact calc_unlock_impact(double mass_yy_kg, double mass_xx_kg, double cot_beta, double u,
                                       bool drive_holds_speed) {
  UnlockImpact r;
  const double c = cot_beta;
  if (drive_holds_speed) {
    r.hinge_speed_m_per_s = -u / c;
    const double Lambda = mass_xx_kg * r.hinge_speed_m_per_s / c;
    r.rail_impulse_Ns = Lambda;
    r.drive_work_J = -Lambda * u;
    r.energy_loss_J = r.drive_work_J - 0.5 * mass_xx_kg * r.hinge_speed_m_per_s * r.hinge_speed_m_per_s;
  } else {
    const double Lambda = -u / (1.0 / mass_yy_kg + c * c / mass_xx_kg);
    r.rail_impulse_Ns = Lambda;
    r.du_m_per_s = Lambda / mass_yy_kg;
    r.hinge_speed_m_per_s = c * Lambda / mass_xx_kg;
    r.energy_loss_J = 0.5 * (mass_yy_kg * r.du_m_per_s * r.du_m_per_s +
                             mass_xx_kg * r.hinge_speed_m_per_s * r.hinge_speed_m_per_s);
  }
  return r;
}

struct DriveRamp {
  double impulse_Ns = 0, work_J = 0;
};
// Lossless start of a driven mass from rest to speed u.
inline DriveRamp calc_drive_ramp(double mass_kg, double u) { return {mass_kg * u, 0.5 * mass_kg * u * u}; }

}  // namespace truss::model
