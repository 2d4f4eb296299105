// The drive laws of the lead screws and the drive train between the motor and the screws
// (docs/model.md §2 "Drive modes"; docs/model-notes.md "Drive train"):
//   velocity: the driven frame moves at the constant speed v; the drive force is an output;
//   torque:   the actuator gives the constant torque M_d at the motor shaft along the run direction;
//   motor:    M = k_d M_stall (1 - omega_m / omega_0), omega_m = N 2 pi (dy/dt) / h along the run
//             direction (k_d the motor's derating, N the gear ratio).
// The train (gear ratio N, gear efficiency eta_g, lead-screw efficiency eta_s driving the load and
// eta_s' backdriven, loss torques T_L at the motor shaft opposing the motion) passes the motor
// torque M to the three screws together as the force along the run direction
//   F = (2 pi N / h) eta_g eta_s (M - T_L)          when M - T_L >= 0 (the motor drives the load),
//   F = (2 pi N / h) (M - T_L) / (eta_g eta_s')     when M - T_L < 0 (the load drives the motor),
// the lead screw's raise and lower torques (T = F h / (2 pi eta), T = F h eta' / (2 pi)) with a gear
// in front; calc_motor_torque_for_force_Nm is its inverse (the torque the motor must give).
// Screw torque M_s = F h / (2 pi): the torque of an ideal screw, what the runs report as drive
// torque. Forces are signed along +y. The defaults are an ideal train (N = 1, every efficiency 1,
// no losses, no derating): then F = 2 pi M / h to the bit.
// These plain structs are also the scene's [drive] options (sim::DriveOptions): one type, one
// default per field.
#pragma once
#include <numbers>

namespace truss::model {

enum class DriveMode { velocity, torque, motor };
enum class Direction { deploy, retract };
const char* to_string(DriveMode);
const char* to_string(Direction);

// +1 when the driven frame moves up (deploy), -1 (retract).
constexpr double calc_direction_sign(Direction d) { return d == Direction::deploy ? 1.0 : -1.0; }

struct DriveParams {
  DriveMode mode = DriveMode::velocity;   // the paper's constant-speed drive
  double speed_m_per_s = 0.1;             // Table 1: v_dep (velocity mode)
  double screw_lead_m = 0.01;             // project default h (paper leaves it open)
  double torque_Nm = 0.01;                // project default: 6.3 N of screw force, above the ~3 N spring peak
  double stall_torque_Nm = 0.02;          // project default motor: 12.6 N stall force
  double no_load_speed_rad_per_s = 75.0;  // project default: 0.119 m/s free-running screw speed
  // The drive train; every default is the ideal train (the paper's drive has none).
  double gear_ratio = 1.0;                // N: motor turns per screw turn
  double gear_efficiency = 1.0;           // eta_g, both directions of the power flow
  double screw_efficiency = 1.0;          // eta_s = tan(lambda) / tan(lambda + phi): the motor drives the load
  double screw_back_efficiency = 1.0;     // eta_s' = tan(lambda - phi) / tan(lambda): the load drives the screw
  double friction_torque_Nm = 0.0;       // F_R at the motor shaft (bearings, seals), against the motion
  double detent_torque_Nm = 0.0;         // H_M: the motor's detent (cogging) amplitude, against the motion
  double hysteresis_torque_Nm = 0.0;     // H_Y at the motor shaft, against the motion
  double harness_torque_Nm = 0.0;        // H_A: the harness's resistance at the motor shaft, against the motion
  double motor_derating = 1.0;           // k_d = k_temperature k_voltage k_end-of-life, on the motor's torque

  // T_L (N m at the motor shaft): the losses that oppose the motion whatever the load.
  double calc_loss_torque_Nm() const {
    return friction_torque_Nm + detent_torque_Nm + hysteresis_torque_Nm + harness_torque_Nm;
  }

  // Screw force (N, along +y) at driven-frame velocity u (torque and motor modes; 0 in velocity
  // mode, where the force is an output). `direction` is calc_direction_sign of the run. The mast
  // moves along the run direction (a phase that would move it back stalls first), so the losses
  // act against it. Written as k M_d f - k T_L, the actuator's torque M_d f and the train's factor
  // k = d (2 pi / h) N eta, so that the ideal train gives the ideal screw's products to the bit.
  // A template on the number type, as model/bay.hpp.
  template <class T>
  T calc_force_N(T u, double direction) const {
    if (mode == DriveMode::velocity) return T(0.0);
    const double to_force = 2.0 * std::numbers::pi / screw_lead_m;
    const double torque = mode == DriveMode::motor ? motor_derating * stall_torque_Nm : torque_Nm;
    T factor = T(1.0);
    if (mode == DriveMode::motor) {
      const T omega = to_force * direction * u;  // screw speed along the run direction
      factor = 1.0 - gear_ratio * omega / no_load_speed_rad_per_s;
    }
    const double loss = calc_loss_torque_Nm();
    const bool drives_load = torque * factor - loss >= 0.0;
    const double k = direction * to_force * gear_ratio *
                     (drives_load ? gear_efficiency * screw_efficiency : 1.0 / (gear_efficiency * screw_back_efficiency));
    return k * torque * factor - k * loss;
  }
  // M_s = F h / (2 pi): the torque of an ideal screw for the force F.
  double calc_torque_Nm(double force_N) const { return force_N * screw_lead_m / (2.0 * std::numbers::pi); }
  // The torque the motor must give (N m at the motor shaft, along the run direction) for the screw
  // force force_along_N along the run direction while the mast moves along it: the inverse of
  // calc_force_N's train, T_L + M_s / (N eta_g eta_s) driving the load, T_L + M_s eta_g eta_s' / N
  // backdriven (M_s < 0).
  double calc_motor_torque_for_force_Nm(double force_along_N) const {
    const double screw = calc_torque_Nm(force_along_N);
    const double train = screw >= 0.0 ? gear_ratio * (gear_efficiency * screw_efficiency)
                                       : gear_ratio / (gear_efficiency * screw_back_efficiency);
    return calc_loss_torque_Nm() + screw / train;
  }
  // The motor's torque (N m at the motor shaft, after derating) at a driven-frame speed along the
  // run direction (motor law above).
  double calc_motor_torque_Nm(double speed_m_per_s) const {
    const double omega = 2.0 * std::numbers::pi / screw_lead_m * speed_m_per_s;
    return motor_derating * stall_torque_Nm * (1.0 - gear_ratio * omega / no_load_speed_rad_per_s);
  }
  // The no-load speed of the screws (rad/s): the motor's over the gear ratio.
  double calc_no_load_screw_speed_rad_per_s() const { return no_load_speed_rad_per_s / gear_ratio; }
};

inline const char* to_string(DriveMode m) {
  switch (m) {
    case DriveMode::velocity: return "velocity";
    case DriveMode::torque: return "torque";
    case DriveMode::motor: return "motor";
  }
  return "?";
}
inline const char* to_string(Direction d) { return d == Direction::deploy ? "deploy" : "retract"; }

}  // namespace truss::model
