// A phase of a stage as the solvers see it (docs/model.md §2: phase A open, phase B on the rail).
// PhaseModel is the narrow interface between a phase's equations and the time-stepping solver:
// any number of generalized coordinates q (the held stack has one, the free stack n - j),
// accelerations and the reported loads at (q, q'), and the scalar functions the events need.
// Nothing outside a model knows the layout of its state.
#pragma once
#include "model/drive.hpp"
#include "model/frames.hpp"
#include "model/params.hpp"

namespace truss::stages {

enum class PhaseKind { open, on_rail };

// Everything a phase needs, fixed for the phase.
struct PhaseContext {
  const model::MastParams* mast = nullptr;
  PhaseKind kind = PhaseKind::open;
  int bay = 0;                        // deploying bay m; driven frame m, lower frame m-1
  double lower_held_height_m = 0;     // open: height of frame m-1 (held); on_rail: of frame m-2
  double locked_mass_kg = 0;          // locked bays above m + tip
  double panel_height_offset_m = 0;   // H = y_m + offset
  model::DriveParams drive;           // drive law
  double direction = 1.0;             // +1 deploy (driven frame up), -1 retract
  double q_end = 0;                   // phase coordinate at the phase's end event
  double sign_q = 1.0;                // +1 if q increases towards q_end
};

// Everything one evaluation of a phase gives: the reported frames, accelerations, loads.
// A template on the number type: PhasePoint (double) everywhere; the held phase's closed form
// also in a dual number type, whose fields then carry their time derivatives.
template <class T>
struct PhasePointT {
  T q = 0, qdot = 0, qddot = 0;  // held phase: its coordinate (y_m or x) and derivatives
  T y_driven_m = 0, y_lower_m = 0;
  T u_m_per_s = 0, w_m_per_s = 0;  // velocities of driven and lower frame
  T hinge_x_m = 0, hinge_y_m = 0;
  T drive_force_N = 0;
  // Drive force (N, along +y) that holds the mast at rest in this configuration: the diagonals'
  // (spring) resistance alone, dU/dy_m along the phase's path (no velocity, no acceleration); for
  // the free stack with the deploying bay in its configuration and the frames below it in static
  // equilibrium (model/static_resistance.hpp). The inertial part of the drive force is
  // drive_force_N - static_drive_force_N.
  T static_drive_force_N = __builtin_nan("");
  T lambda_N = 0;                // rail multiplier (0 off the rail)
  T pin_force_N = 0;
  T diagonal_tension_N = 0;      // largest tension of one diagonal in the moving bays
  T kinetic_energy_J = 0;
  T potential_energy_J = 0;      // diagonals of the moving bays (m and, on the rail, m-1)
  T rail_residual_m = 0;
  // Mass matrix in the phase's coordinates: open: mass_yy only; on_rail: (y_m, x) entries.
  T mass_yy = 0, mass_yx = 0, mass_xx = 0;
  T rail_slope = 0;              // on_rail: gamma = c + x/s = df/dx = -Y'(x)
  // Free stack, open phase: distance of the hinge from the rail line, f sin(beta) (m; > 0 on
  // the stack's side); +inf where not tracked (held stack, on the rail).
  T rail_distance_m = __builtin_inf();
  // Free stack: smallest bay opening D_i of the moving bays (m); < 0 when frames have passed
  // through each other (or frame 1 through the floor): contacts are off. +inf where not tracked.
  T min_bay_opening_m = __builtin_inf();
};
using PhasePoint = PhasePointT<double>;

// Which fields of a point an evaluation fills (the rest keep their defaults): all of them; the
// loads, speeds, masses and rail residual (what the peaks need); or what time stepping needs, the
// accelerations, the drive force and the speeds.
enum class PointFields { all, loads, motion };

// Work space of a model evaluation, owned by the caller (the model functions stay pure).
using PhaseScratch = model::FrameSystem;

// The residual form of a phase's equations (DAE solvers: IDA), assembled without solving:
//   M(q) q'' = r(q, q') + sum_j mu_j c_j(q),   c_j(q)' q'' = s_j(q, q'),   j < num_multipliers,
// M symmetric tridiagonal (diag, sub as model/frames.hpp), r with the drive force of the torque and
// motor modes, multipliers mu_j: the rail's lambda (on the rail) and, in velocity mode, the drive
// force F (its constraint keeps the driven frame's speed). The drive force is the multiplier
// drive_multiplier, or drive_force_N (torque, motor) when that is -1.
// Every term is local, so that the DAE's Jacobian is banded (IDA's banded solver): diag[i], sub[i]
// and rhs[i] depend on q and q' of coordinates i-1..i+1 only; the c_j are zero but on the last two
// coordinates, and c_j, s_j, driven_speed_m_per_s and drive_force_N depend on q and q' of those
// two only (tests/numeric/test_free_ida.cpp checks the band by perturbation).
struct PhaseDaeTerms {
  static constexpr int kMaxMultipliers = 2;
  Eigen::VectorXd diag, sub, rhs;
  int num_multipliers = 0;
  Eigen::VectorXd c[kMaxMultipliers];
  double s[kMaxMultipliers] = {0.0, 0.0};
  int drive_multiplier = -1;
  double drive_force_N = 0;
  double driven_speed_m_per_s = 0;
};

class PhaseModel {
 public:
  virtual ~PhaseModel() = default;
  virtual int dof() const = 0;
  virtual const PhaseContext& context() const = 0;
  // Accelerations (dof values into qddot) and the reported point at (q, q').
  virtual PhasePoint calc_point(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const = 0;
  // Accelerations (dof values into qddot) at (q, q') and the drive's power F dy_m/dt (W): what
  // time stepping needs of a point (PointFields::motion), nothing else computed.
  virtual double calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const {
    const PhasePoint p = calc_point(q, qdot, qddot, scratch);
    return p.drive_force_N * p.u_m_per_s;
  }
  // The point as the peak tracker needs it at a step end (PointFields::loads: the loads, speeds,
  // masses and rail residual; the energies and the hinge may be left out); by default all of it.
  virtual PhasePoint calc_loads(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const {
    return calc_point(q, qdot, qddot, scratch);
  }
  // Driven-frame velocity dy_m/dt (m/s).
  virtual double calc_driven_speed_m_per_s(const double* q, const double* qdot) const = 0;
  // Rises through zero at the phase's end event; and its second time derivative (from q'').
  virtual double calc_end_gap(const double* q) const = 0;
  virtual double calc_end_gap_acceleration(const double* qddot) const = 0;
  // Puts q exactly on the end surface once the event is located.
  virtual void snap_to_end(double* q) const = 0;
  // Further events that end the phase early (free stack: rail miss, singular bay, watched
  // crossings): each rises through zero when it fires. The held phases have none.
  virtual int num_stop_events() const { return 0; }
  virtual void calc_stop_events(const double* /*q*/, const double* /*qdot*/, double* /*g*/) const {}
  // Whether stop event k ends the phase where the loads hold a term that grows without bound (a bay
  // within 1e-4 l_s of straight): its peaks are then taken at the stop's own state (PhasePeaks).
  virtual bool is_singular_stop(int /*k*/) const { return false; }
  // Grazing touches: conditions h_k(q) >= 0 that end the phase (its end event or a stop event) and
  // that a step can pass in and out of between its two ends, unseen by the events' sign test there
  // (a pin that dips into the rail and out, a bay that straightens and folds back). At (q, q') the
  // model gives every h_k and a rate with the sign of dh_k/dt. A step with h_k < 0 at both ends,
  // h_k rising at its start and falling at its end, is searched for a maximum h_k >= 0 on its dense
  // output; the touch is where h_k first reaches 0 (phase_dynamic.cpp).
  virtual int num_touches() const { return 0; }
  virtual void calc_touches(const double* /*q*/, const double* /*qdot*/, double* /*h*/, double* /*rate*/) const {}
  // The event touch k is: -1 the phase's end event, else the index of the stop event.
  virtual int find_touch_event(int /*k*/) const { return -1; }
  // Residual form (PhaseDaeTerms) at (q, q'): the number of multipliers, -1 when the model has
  // none (the held phases); calc_dae_terms returns false where the terms are not defined.
  virtual int num_multipliers() const { return -1; }
  // For each coordinate q_k, the distance it can move from q with the equations smooth (len, dof
  // values): the free stack's mass matrix holds G(D) ~ 1 / (2 l - D) of every bay that q_k opens, so
  // the distance of those bays to straight (IDA's difference-quotient Jacobian resolves it). false:
  // nothing limits any coordinate (the held phases).
  virtual bool calc_smooth_lengths(const double* /*q*/, double* /*len*/) const { return false; }
  // For each coordinate q_k, the factor in (0, 1] of its error tolerance (DaeForm::calc_error_factors):
  // a frame height that opens a bay near straight fixes that bay's configuration, its hinge offset
  // x, only to second order (D = 2 sqrt(l^2 - x^2)), so its error is measured in x. false: 1.
  virtual bool calc_error_factors(const double* /*q*/, double* /*f*/) const { return false; }
  // Heights of all frames 0..n (m) at q, for the per-frame history; false: not tracked (held
  // stack, whose frames below the deploying bay are at their stowed or lock heights).
  virtual bool calc_frame_heights(const double* /*q*/, double* /*y*/) const { return false; }
  virtual bool calc_dae_terms(const double* /*q*/, const double* /*qdot*/, PhaseScratch& /*scratch*/,
                              PhaseDaeTerms& /*out*/) const { return false; }
};

}  // namespace truss::stages
