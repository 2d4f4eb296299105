// The motorisation check of ECSS-E-ST-33-01C (6 March 2009), Space engineering - Mechanisms,
// clause 4.7.5.3.1 "Motorization factors" and Table 4-2 (docs/model-notes.md "Motorisation check"):
// each resistance is multiplied by its uncertainty factor and the actuation torque must be at least
//   T_min = MF (k_S S + k_F F_R + k_M H_M + k_Y H_Y + k_A H_A) + k_D T_D
// over the whole travel, S the spring resistance, F_R friction, H_M the motor's magnetic losses
// (its detent torque), H_Y hysteresis, H_A the harness, T_D the inertial resistance under the
// acceleration required (a prescribed speed); every torque at the motor shaft. The defaults are the
// clause's MF = 2 and k_D = 1.25 and Table 4-2's "theoretical" column (1.2, 3, 1.5, 3, 3); its
// "measured" column is 1.2, 1.5, 1.2, 1.5, 1.5. The table's inertia of an accelerated reference
// frame (1.1) and adhesion (3) have no term in this model. Later issues of the standard (Rev.1
// 2017, Rev.2 2019) may set them otherwise: the factors are the scene's [motorisation] keys.
// The margin is T_available / T_min - 1: positive when the actuator meets the factors.
#pragma once
#include <cmath>
#include <limits>

#include "model/drive.hpp"

namespace truss::model {

// The factors of the check (the scene's [motorisation] table: one type, one default per field).
struct MotorisationFactors {
  double factor = 2.0;             // MF, clause 4.7.5.3.1
  double spring_factor = 1.2;      // k_S, Table 4-2 (both columns)
  double inertia_factor = 1.25;    // k_D on T_D, clause 4.7.5.3.1
  double friction_factor = 3.0;    // k_F, Table 4-2 theoretical (measured 1.5)
  double detent_factor = 1.5;      // k_M, motor magnetic losses, Table 4-2 theoretical (measured 1.2)
  double hysteresis_factor = 3.0;  // k_Y, Table 4-2 theoretical (measured 1.5)
  double harness_factor = 3.0;     // k_A, Table 4-2 theoretical (measured 1.5)
};

// The resistances at the motor shaft (N m, each >= 0 or NaN where not known).
struct MotorisationTorques {
  double spring_Nm = 0, inertial_Nm = 0, friction_Nm = 0, detent_Nm = 0, hysteresis_Nm = 0, harness_Nm = 0;
};

// The resistances of a run: its peak spring and inertial screw torques along the run direction
// (a helping spring or a decelerating mast counts 0: the clause factors resistances) referred to
// the motor through the train driving the load, M_s / (N eta_g eta_s), and the train's loss
// torques. inertial_screw_Nm is 0 where no acceleration is required.
inline MotorisationTorques calc_motorisation_torques(const DriveParams& d, double spring_screw_Nm, double inertial_screw_Nm) {
  const double train = d.gear_ratio * (d.gear_efficiency * d.screw_efficiency);
  auto resist = [](double v) { return v > 0.0 || std::isnan(v) ? v : 0.0; };  // NaN stays NaN
  return {resist(spring_screw_Nm) / train, resist(inertial_screw_Nm) / train, d.friction_torque_Nm,
          d.detent_torque_Nm, d.hysteresis_torque_Nm, d.harness_torque_Nm};
}

// T_min (N m at the motor shaft).
inline double calc_required_torque_Nm(const MotorisationTorques& r, const MotorisationFactors& f) {
  return f.factor * (f.spring_factor * r.spring_Nm + f.friction_factor * r.friction_Nm + f.detent_factor * r.detent_Nm +
                     f.hysteresis_factor * r.hysteresis_Nm + f.harness_factor * r.harness_Nm) +
         f.inertia_factor * r.inertial_Nm;
}

// The actuator's torque the check judges (N m at the motor shaft): velocity mode, the motor's at
// the prescribed speed (its line, derated); motor mode, its derated stall torque, what it gives
// wherever the mast holds it; torque mode, the constant torque.
inline double calc_available_torque_Nm(const DriveParams& d) {
  switch (d.mode) {
    case DriveMode::velocity: return d.calc_motor_torque_Nm(d.speed_m_per_s);
    case DriveMode::motor: return d.motor_derating * d.stall_torque_Nm;
    case DriveMode::torque: return d.torque_Nm;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// The motor's stall torque (N m, its declared value, before derating) with which it meets the
// factors exactly: T_min over the torque judged per N m of stall torque, k_d (1 - N omega / omega_0)
// in velocity mode, k_d in motor mode. +inf when the prescribed speed is at or above the motor's
// no-load speed (no stall torque gives it); NaN in torque mode (no motor line) and when nothing
// resists.
inline double calc_needed_stall_torque_Nm(const DriveParams& d, double required_Nm) {
  if (d.mode == DriveMode::torque || !(required_Nm > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double per_stall = calc_available_torque_Nm(d) / d.stall_torque_Nm;
  if (!(per_stall > 0.0)) return std::numeric_limits<double>::infinity();
  return required_Nm / per_stall;
}

// T_available / T_min - 1 (1): > 0 when the actuator meets the factors; NaN when nothing resists
// (T_min <= 0: an ideal train whose springs help, no factor to meet) or a term is not known.
inline double calc_motorisation_margin(double available_Nm, double required_Nm) {
  if (!(required_Nm > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return available_Nm / required_Nm - 1.0;
}

}  // namespace truss::model
