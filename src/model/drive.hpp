// The three drive laws of the lead screws (docs/model.md §2, "Drive modes"):
//   velocity: the driven frame moves at the constant speed v; the drive force is an output;
//   torque:   constant screw torque M_d along the run direction, force F = 2 pi M_d / h;
//   motor:    M = M_stall (1 - omega / omega_0), omega = 2 pi (dy/dt) / h along the run direction.
// Force and torque of the three screws together: M = F h / (2 pi). Forces are signed along +y.
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

  // Screw force (N, along +y) at driven-frame velocity u (torque and motor modes; 0 in velocity
  // mode, where the force is an output). `direction` is calc_direction_sign of the run.
  // A template on the number type, as model/bay.hpp.
  template <class T>
  T calc_force_N(T u, double direction) const {
    const double to_force = 2.0 * std::numbers::pi / screw_lead_m;
    switch (mode) {
      case DriveMode::torque: return T(direction * to_force * torque_Nm);
      case DriveMode::motor: {
        const T omega = to_force * direction * u;  // screw speed along the run direction
        return direction * to_force * stall_torque_Nm * (1.0 - omega / no_load_speed_rad_per_s);
      }
      case DriveMode::velocity: break;
    }
    return T(0.0);
  }
  // M = F h / (2 pi)
  double calc_torque_Nm(double force_N) const { return force_N * screw_lead_m / (2.0 * std::numbers::pi); }
  // The motor's torque at a driven-frame speed along the run direction (N m, motor law above).
  double calc_motor_torque_Nm(double speed_m_per_s) const {
    const double omega = 2.0 * std::numbers::pi / screw_lead_m * speed_m_per_s;
    return stall_torque_Nm * (1.0 - omega / no_load_speed_rad_per_s);
  }
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
