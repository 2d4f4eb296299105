// Phase B of the free stack (docs/model.md §2-§3; paper eqs. 19-20, corrected): the pin of bay m slides
// in the rail. Coordinates p = (y_lo, .., y_{m-1}, x): the frame heights below the deploying bay
// and its hinge offset x, regular at the lock (docs/model.md §3, numerical trap). With
//   y_m = y_{m-1} + 2 s(x),  s = sqrt(l^2 - x^2),  y_m' = y_{m-1}' - k x',  k = 2x/s,
//   y_m'' = y_{m-1}'' - k x'' - k_x x'^2,  k_x = 2 l^2 / s^3,
// the frame-height system A y'' = R (model/frames.hpp, bay m's strut term written as g(x) x'^2,
// model/bay.hpp) becomes, with T the Jacobian of y(p), M_p = T' A T + 2 g e_x e_x':
//   M_p[m-1,m-1] = A_ll + 2 A_ml + A_mm,  M_p[x,m-1] = -k (A_ml + A_mm),  M_p[x,x] = k^2 A_mm + 2 g,
//   rhs[m-1] = R_l + R_m - (A_ml + A_mm) h,  rhs[x] = -k (R_m - A_mm h) - g' x'^2,  h = -k_x x'^2,
// which is still tridiagonal (x couples with y_{m-1} only). The rail f = y_{m-1} + s(x) - y_r + c x
// (c = cot beta) has the regular gradient a = (.., 1, c - x/s), and the paper's bordered system
//   [M_p  a] [p''    ]   [rhs + F b]
//   [a'   0] [-lambda] = [s_a      ],   s_a = (l^2/s^3) x'^2 - 2 alpha f' - alpha^2 f,
// (Baumgarte stabilisation at rate alpha against drift; b = dy_m/dp = (.., 1, -k) carries the
// drive) is solved directly: two tridiagonal solves and a scalar (model/tridiagonal.hpp). In
// velocity mode y_m'' = 0 is a second row b' p'' = k_x x'^2 - alpha (y_m' - v) with the drive force
// as its multiplier: three solves and a 2x2 system. Pin force |lambda| / (3 sin beta).
// Stack contacts on (free_stack/free_contacts.hpp): p = (Y_c of the clusters of frames lo..m-1, x),
// the frame-height system reduced to the clusters (model/contacts.hpp) before the map to x; stop
// events 1 and 2 are the contact landing and lift-off.
#pragma once
#include <vector>

#include "model/frames.hpp"
#include "model/rail.hpp"
#include "model/tridiagonal.hpp"
#include "free_stack/free_contacts.hpp"
#include "free_stack/free_phase_work.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

class FreePhaseB final : public PhaseModel {
 public:
  // ctx.bay = m; frames lo..m-1 and x move; frames below lo are held at held_height_m.
  // alpha: Baumgarte rate (1/s) of the rail and drive-speed constraints. bays: the mast's bay
  // constants (model::calc_bay_table(*ctx.mast)), kept by the caller for the phase's life.
  FreePhaseB(const PhaseContext& ctx, int lo, double held_height_m, double alpha_per_s,
             const std::vector<model::BayConstants>& bays);
  int dof() const override { return layout_.clusters() + 1; }
  // Stack contacts: clusters of frames lo..m-1.
  void set_contacts(ContactLayout layout) {
    layout_ = std::move(layout);
    work_.memo.keep_system = layout_.enabled;
    work_.memo.valid = false;
  }
  ContactWatch calc_contact_watch(const double* q, const double* qdot) const;
  // The mass matrix in p (diag, sub; the contact impacts).
  void calc_mass(const double* q, const double* qdot, Eigen::VectorXd& diag, Eigen::VectorXd& sub) const;
  const PhaseContext& context() const override { return ctx_; }
  PhasePoint calc_point(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override {
    return evaluate(q, qdot, qddot, scratch, nullptr, nullptr, PointFields::all);
  }
  // The peaks' part of calc_point (PointFields::loads): all but the kinetic and potential energy.
  PhasePoint calc_loads(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override {
    return evaluate(q, qdot, qddot, scratch, nullptr, nullptr, PointFields::loads);
  }
  // Time stepping's part of calc_point: the accelerations and the drive power F y_m'.
  double calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override;
  double calc_driven_speed_m_per_s(const double* q, const double* qdot) const override;
  double calc_end_gap(const double* q) const override { return ctx_.sign_q * (q[dof() - 1] - ctx_.q_end); }
  double calc_end_gap_acceleration(const double* qddot) const override { return ctx_.sign_q * qddot[dof() - 1]; }
  void snap_to_end(double* q) const override { q[dof() - 1] = ctx_.q_end; }
  // Stop event 0 (docs/model.md §2, singular configuration): a moving bay below m comes within
  // FreePhaseA::kStraightFraction l_s of straight (largest kStraightFraction l_i - x_i).
  int num_stop_events() const override { return layout_.enabled ? 3 : 1; }
  bool is_singular_stop(int k) const override { return k == 0; }
  void calc_stop_events(const double* q, const double* qdot, double* g) const override;
  // Touches (phase.hpp): each moving bay below m straightening (stop event 0), as FreePhaseA's.
  int num_touches() const override { return ctx_.bay - std::max(lo_, 1); }
  void calc_touches(const double* q, const double* qdot, double* h, double* rate) const override;
  int find_touch_event(int) const override { return 0; }
  // Rail function f (m) at p: 0 on the rail.
  double calc_rail_function_m(const double* q) const;
  // Residual form (phase.hpp): the rail's lambda with a, s_a, and in velocity mode the drive force
  // with b, s_b (the bordered rows above, assembled without solving).
  int num_multipliers() const override { return ctx_.drive.mode == model::DriveMode::velocity ? 2 : 1; }
  bool calc_dae_terms(const double* q, const double* qdot, PhaseScratch& scratch, PhaseDaeTerms& out) const override;
  bool calc_frame_heights(const double* q, double* y) const override;
  // Per cluster of frames lo..m-1, the smallest distance to straight of the bays below m it opens
  // (FreePhaseA::calc_straight_distances); x is regular up to the lock: unlimited.
  bool calc_smooth_lengths(const double* q, double* len) const override;
  // Per cluster of frames lo..m-1, FreePhaseA::calc_hinge_factors over the bays below m; x: 1.
  bool calc_error_factors(const double* q, double* f) const override;

 private:
  bool assemble(const double* q, const double* qdot, PhaseScratch& sys, std::vector<double>& ys, std::vector<double>& vs,
                PhaseDaeTerms& t) const;
  PhaseContext ctx_;
  model::ActiveFrames active_;
  int lo_;
  double held_height_m_, alpha_;
  ContactLayout layout_;
  double chain_slack_span_m_ = 0;  // of bays 1..m-1 (the static drive force, model/static_resistance.hpp)
  model::RailConstants rail_;   // cot(beta), y_r, 3 sin(beta) of the phase's rail
  mutable FreePhaseWork work_;  // scratch of the evaluations (free_phase_work.hpp)
  // The bordered system at (q, q') (assemble) solved: accelerations into qddot, the rail's lambda
  // and the drive force; the terms (mass matrix) and the frame heights point_ys stay in work_.
  struct Motion {
    double drive_force_N, lambda_N;
  };
  Motion solve_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const;
  PhasePoint evaluate(const double* q, const double* qdot, double* qddot, PhaseScratch& sys, Eigen::VectorXd* mass_diag,
                      Eigen::VectorXd* mass_sub, PointFields fields) const;
  // Heights and velocities of frames max(lo - 1, 0)..m (frame m from x).
  void expand_frames(const double* q, const double* qdot, std::vector<double>& ys, std::vector<double>& vs) const;
};

}  // namespace truss::stages
