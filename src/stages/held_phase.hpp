// One phase of a held-stack stage, as a 1-DOF system in a regular coordinate q:
//   open    (hinge off the rail, docs/model.md §2 phase A): q = y_m, lower frame held at rest;
//   on_rail (phase B): q = x, the hinge offset of bay m, with y_m = Y(x), y_{m-1} = Z(x)
//            (rail.hpp) and frame m-2 held: regular at the lock x = 0 (docs/model.md §3, trap).
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
#include "model/frames.hpp"
#include "model/impacts.hpp"
#include "model/params.hpp"
#include "model/rail.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

// Evaluates the phase at (q, qdot). In velocity mode qdot must be the prescribed kinematics
// (y_m' = direction * v) and q'' is computed from it; otherwise the drive law gives F.
// Pure: the frame-system work space is the caller's.
class HeldPhase final : public PhaseModel {
 public:
  explicit HeldPhase(const PhaseContext& ctx) : HeldPhase(ctx, model::calc_rail_constants(ctx.mast->rail)) {}
  HeldPhase(const PhaseContext& ctx, const model::RailConstants& rail);  // the rail's constants, computed once
  const model::RailConstants& get_rail_constants() const { return rail_; }
  // In double, or in numerics::Dual (q, qdot seeded with their time derivatives: every field of
  // the point then carries its time derivative).
  template <class T>
  PhasePointT<T> calc_point_t(T q, T qdot) const;
  // Velocity mode: the point at q with the driven frame at speed u_m_per_s along +y (on the rail
  // xi = u / Y'(x), from the same rail kinematics the point uses).
  template <class T>
  PhasePointT<T> calc_point_at_speed_t(T q, double u_m_per_s, PointFields fields = PointFields::all) const;
  PhasePoint calc_point(double q, double qdot, PhaseScratch& scratch) const;
  // Convenience for tests and one-off evaluations: allocates its own work space.
  PhasePoint calc_point(double q, double qdot) const;
  double strut_length_m() const { return ctx_.mast->bay(ctx_.bay).strut_length_m; }
  // Driven-frame velocity for the phase coordinate's rate (open: q' itself; on the rail Y'(x) x').
  double calc_driven_speed_m_per_s(double q, double qdot) const;

  // PhaseModel: one coordinate.
  int dof() const override { return 1; }
  const PhaseContext& context() const override { return ctx_; }
  PhasePoint calc_point(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override {
    const PhasePoint p = calc_point(q[0], qdot[0], scratch);
    qddot[0] = p.qddot;
    return p;
  }
  double calc_driven_speed_m_per_s(const double* q, const double* qdot) const override {
    return calc_driven_speed_m_per_s(q[0], qdot[0]);
  }
  double calc_end_gap(const double* q) const override { return ctx_.sign_q * (q[0] - ctx_.q_end); }
  double calc_end_gap_acceleration(const double* qddot) const override { return ctx_.sign_q * qddot[0]; }
  void snap_to_end(double* q) const override { q[0] = ctx_.q_end; }
  double calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override;
  PhasePoint calc_loads(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override;

 private:
  template <class T>
  PhasePointT<T> calc_open(T y, T u, PointFields fields = PointFields::all) const;
  template <class T>
  PhasePointT<T> calc_on_rail(const model::OnRailKinematicsT<T>& kin, T xi,
                              PointFields fields = PointFields::all) const;
  model::OnRailKinematics calc_kinematics(double x) const { return model::calc_on_rail(rail_, strut_length_m(), x); }
  PhaseContext ctx_;
  model::RailConstants rail_;
  model::ActiveFrames active_;
  double b2_m_ = 0, b2_lower_ = 0;    // diagonal offsets^2 of bays m and m-1
};

// y-space mass matrix of frames (m-1, m) with bay m written in frame heights (regular off the
// lock): the held stack's rail-entry and rail-exit impacts (model/impacts.hpp).
model::TwoFrameMass calc_two_frame_mass(const model::MastParams& mast, int m, double locked_mass_kg, double panel_height_offset_m,
                                        double y_lower, double y_driven);

}  // namespace truss::stages
