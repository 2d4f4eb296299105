// Run result (a layer below sim/, so that the stages fill it without a cycle): what one simulated deployment or retraction reports (docs/model.md §5).
// Units are in the field names. Times are seconds from the start of the run.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace truss::stages {

// wall_time_limit: the run was stopped by its wall-time cap (stages::RunOptions::max_wall_time_s); unlike
// the other statuses it depends on the machine, not only on the inputs.
// solver_failure: the integrator could not continue (non-finite state, step-size underflow, a
// CVODE error flag); step_limit is only the step cap. inaccurate: the run completed but its energy
// balance is off by more than its tolerance allows (stages/accuracy.hpp), so its numbers are not
// promised. New statuses go at the end: the codes are stored in journals and HDF5 files.
enum class RunStatus { ok, rail_miss, stall, singular_configuration, step_limit, invalid_input, wall_time_limit,
                       solver_failure, inaccurate };
const char* to_string(RunStatus);
constexpr int kRunStatusCount = 9;

struct BayResult {
  int bay = 0;                         // bay index i = 1..n
  // Deployment: rail entry / lock. Retraction: rail exit (landing of the lower frame) / unlock.
  double entry_time_s = NAN_INIT();
  double lock_time_s = NAN_INIT();
  double latch_energy_J = NAN_INIT();       // strut radial KE lost at the latch (or paid at unlock)
  double entry_impulse_Ns = NAN_INIT();     // rail impulse per pin at rail entry (deploy)
  double landing_impulse_Ns = NAN_INIT();   // stack impulse on the lower frame at rail exit (retract)
  double entry_drive_impulse_Ns = NAN_INIT();  // drive impulse at rail entry / exit (velocity mode)
  double unlock_impulse_Ns = NAN_INIT();    // rail impulse per pin at the unlock (retract; 0 from rest in torque/motor)
  double entry_energy_loss_J = NAN_INIT();  // energy lost in the rail-entry (or landing) impact
  double peak_drive_force_N = NAN_INIT();   // peak of the smooth drive force in this bay's stage
  double peak_drive_force_time_s = NAN_INIT();
  double peak_pin_force_N = NAN_INIT();     // peak rail normal force on one pin in this stage
  double peak_pin_force_time_s = NAN_INIT();
  static constexpr double NAN_INIT() { return __builtin_nan(""); }
};

struct TimeHistory {
  std::vector<double> t_s;
  std::vector<int> bay;                  // the bay whose stage is running
  std::vector<double> y_driven_m;        // driven frame height
  std::vector<double> y_lower_m;         // lower frame height (frame below the deploying bay)
  std::vector<double> hinge_x_m;         // hinge radial offset of the deploying bay
  std::vector<double> hinge_y_m;         // hinge height of the deploying bay
  std::vector<double> drive_force_N;
  std::vector<double> drive_torque_Nm;
  std::vector<double> pin_force_N;       // rail normal force on one pin (0 off the rail)
  std::vector<double> diagonal_tension_N;  // tension in one diagonal of the deploying bay
  std::vector<double> driven_speed_m_per_s;
  // Free stack: heights of frames 0..n per row (row-major, rows x n_frames, m); empty otherwise.
  std::vector<double> frame_height_m;
  int n_frames = 0;
  double step_s = 0.0;                   // grid step of the rows (output_step_s, doubled at each row cap)
  std::size_t size() const { return t_s.size(); }
};

struct RunResult {
  RunStatus status = RunStatus::ok;
  std::string message;                    // human-readable reason; empty when ok
  std::string direction = "deploy";
  std::string drive_mode = "velocity";
  int n_bays = 0;
  int bays_completed = 0;                 // locked (deploy) or stowed (retract) bays

  double deploy_time_s = NAN_INIT();      // time of the last lock (or end of retraction); NaN if not reached
  double end_time_s = NAN_INIT();         // time at which the run ended, whatever its status
  double peak_drive_force_N = NAN_INIT();
  double peak_drive_force_time_s = NAN_INIT();
  int peak_drive_force_bay = 0;
  double min_drive_force_N = NAN_INIT();
  double min_drive_force_time_s = NAN_INIT();
  int min_drive_force_bay = 0;
  double peak_drive_torque_Nm = NAN_INIT();
  double min_drive_torque_Nm = NAN_INIT();
  // Velocity mode: the torque the scene's motor (drive.stall_torque_Nm, no_load_speed) gives at
  // the prescribed speed, from the one motor law (model/drive.hpp); NaN in torque and motor modes.
  double motor_torque_at_speed_Nm = NAN_INIT();
  // Velocity mode: the motor's quasi-static stall margin (docs/model-notes.md "Motor torque margin";
  // N m, > 0 safe): motor_torque_at_speed_Nm - peak_drive_torque_Nm, negative when the drive needs
  // more torque at some instant than the motor gives at the prescribed speed. NaN in the other modes.
  double motor_torque_margin_Nm = NAN_INIT();
  // The torque the motor must give (N m at the motor shaft, along the run direction, peak over the
  // smooth motion): the peak drive force along the run direction through the drive train's
  // inverse, with its losses (model/drive.hpp; the peak drive torque for an ideal train).
  double peak_motor_torque_Nm = NAN_INIT();
  // The drive torque split into its resistances (the three screws together, along the run
  // direction, peaks over the smooth motion; impulses apart): static = the torque that holds the
  // mast at rest in each configuration (the diagonals' springs, the model's only resistance; the
  // free stack: with the deploying bay in its configuration, the frames below it in static
  // equilibrium), and inertial = drive torque - static (what accelerates the mast).
  double peak_static_drive_torque_Nm = NAN_INIT();
  double peak_inertial_drive_torque_Nm = NAN_INIT();
  // The motorisation check of ECSS-E-ST-33-01C 4.7.5.3.1 (model/motorisation.hpp; docs/model-notes.md
  // "Motorisation check"), every drive mode: T_min from the peaks above referred to the motor and the
  // train's losses, each with its factor (N m at the motor shaft); the actuator's torque it is
  // judged by (N m); the margin T_available / T_min - 1 (1, > 0 when the factors are met; NaN
  // when nothing resists); and the motor's stall torque that meets them exactly (N m, before
  // derating; velocity and motor modes).
  double motorisation_required_torque_Nm = NAN_INIT();
  double motorisation_available_torque_Nm = NAN_INIT();
  double motorisation_margin = NAN_INIT();
  double motorisation_stall_torque_Nm = NAN_INIT();
  double peak_pin_force_N = NAN_INIT();
  double peak_pin_force_time_s = NAN_INIT();
  int peak_pin_force_bay = 0;
  double peak_diagonal_tension_N = NAN_INIT();
  double peak_latch_energy_J = NAN_INIT();  // largest latch energy of any bay (deploy) / unlock (retract)
  double peak_driven_speed_m_per_s = NAN_INIT();

  double drive_work_J = 0.0;              // smooth part + impulses
  double drive_work_smooth_J = 0.0;       // integral of F dy over the smooth motion
  double drive_work_impulses_J = 0.0;     // work of the start, rail-entry and unlock drive impulses
  double start_drive_impulse_Ns = 0.0;    // velocity mode: impulse that starts the driven part
  double energy_lost_J = 0.0;             // all impacts: entries, exits, latches, unlocks, landings
  double kinetic_energy_start_J = 0.0;
  double kinetic_energy_end_J = 0.0;
  double potential_energy_start_J = 0.0;
  double potential_energy_end_J = 0.0;
  double energy_residual_J = NAN_INIT();  // W - dT - dU - E_lost
  double max_rail_residual_m = 0.0;       // largest |f| on the rail (0 by construction when exact)
  // Rail miss (free stack, docs/model.md §2): the bay that missed, the closest approach of its hinge to
  // the rail line and its time, and the time the hinge rose above the rail's top y_r (NaN if not).
  int rail_miss_bay = 0;
  double rail_miss_closest_approach_m = NAN_INIT();
  double rail_miss_closest_approach_time_s = NAN_INIT();
  double rail_miss_above_rail_top_time_s = NAN_INIT();
  // The rail margin (free-stack deployment, docs/model-notes.md "Rail margin"; m, > 0 safe): on a
  // rail miss minus the closest approach, else the smallest over the bays' entries of how deep the
  // uncaptured pin would have dipped below the rail line (phase A continued over one strut length of
  // drive travel); NaN for the held stack and retractions.
  double rail_margin_m = NAN_INIT();
  // Free stack without contacts (the paper's literal model): the smallest opening D_i of any bay
  // over the run, its time and bay; negative when frames passed through each other or frame 1
  // through the floor. NaN (bay 0) for the held stack.
  double min_bay_opening_m = NAN_INIT();
  double min_bay_opening_time_s = NAN_INIT();
  int min_bay_opening_bay = 0;
  // Free stack with stack contacts (stack.contacts = true): landings (plastic impacts of a frame
  // on the one below it or on the resting stack), lift-offs, and the energy the landings lost.
  long contact_landings = 0;
  long contact_lift_offs = 0;
  double contact_energy_loss_J = 0.0;

  long steps = 0;                         // accepted integrator steps (0 in closed-form mode)
  long rejected_steps = 0;
  long rhs_evals = 0;                     // model evaluations (right-hand sides or closed forms)
  double wall_time_s = 0.0;

  std::vector<BayResult> bays;            // bays[0] is bay 1
  TimeHistory history;                    // empty unless output_step_s > 0

  static constexpr double NAN_INIT() { return __builtin_nan(""); }
  std::string to_string() const;          // short human-readable report
};

}  // namespace truss::stages
