// Phase A of the free stack (docs/model.md §2 "free", paper eq. 6 corrected in docs/model.md §3): every
// frame below the driven frame m is a generalized coordinate, frame 0 is held at its height until
// bay 1's rail takes it. Coordinates q = (y_lo, .., y_m), lo = 1 (or the lowest frame the
// stage moves); the tridiagonal system
//   M(y) y'' = r(y, y') + Q(y) + F e_m        (model/frames.hpp: M, r, Q for frames lo..m)
// is solved in O(n) per right-hand side (model/tridiagonal.hpp; no dense matrix).
//   torque / motor drive: F from the drive law, all m - lo + 1 accelerations from the solve;
//   velocity drive: y_m'' = 0 (the driven frame keeps the prescribed speed), the free block
//     lo..m-1 is solved with y_m'' = 0, and F = M[m,m-1] y''_{m-1} - r_m - Q_m (inverse dynamics).
// The phase ends when the hinge of bay m meets the rail: f = y_h - y_l + cot(beta)(x_h - x_l)
// falls through 0 (end gap -f rises), with x_h = (1/2) sqrt(4 l^2 - D_m^2), y_h = (y_m + y_{m-1})/2;
// in a retraction (ctx.direction < 0) when the driven frame is back down at ctx.q_end.
// Stopping rules (docs/model.md §2), as stop events rising through zero:
//   past_miss_height   y_m - (y_r + 3 l_m): the driven frame passes the lock height y_r + l_m plus
//                      one bay 2 l_m without rail entry (rail miss);
//   deploying_straight kStraightFraction l_m - x_m: bay m straightens without rail entry (rail miss);
//   singular_bay       kStraightFraction l_i - x_i, largest over the moving bays i < m (singular);
//   above_rail_top     y_h - y_r (watched only: the time the hinge rises above the rail's top, x = 0).
// Touches (phase.hpp; a step can pass in and out of them unseen by the sign test at its ends): the
// rail, h = -f with rate -f' = c D (u - w)/(4 x) - (u + w)/2 (deployment: the end event), and each
// moving bay i, h = kStraightFraction l_i - x_i with rate D_i D_i' (bay m: deploying_straight,
// the others: singular_bay).
//   contact_landing, contact_lift_off (stack contacts on, free_stack/free_contacts.hpp): the state is
//                      then one height per cluster of frames in closed contact (q = (Y_c), frames
//                      below lo rest on the floor), the mass matrix reduced by model/contacts.hpp.
// An event not watched returns -1 (never rises).
#pragma once
#include <vector>

#include "model/frames.hpp"
#include "model/rail.hpp"
#include "model/tridiagonal.hpp"
#include "free_stack/free_contacts.hpp"
#include "free_stack/free_phase_work.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

class FreePhaseA final : public PhaseModel {
 public:
  // ctx.bay = m; frames lo..m move; frames below lo are held at height held_height_m. bays: the
  // mast's bay constants (model::calc_bay_table(*ctx.mast)), kept by the caller for the phase's life.
  FreePhaseA(const PhaseContext& ctx, int lo, double held_height_m, const std::vector<model::BayConstants>& bays);
  int dof() const override { return layout_.clusters(); }
  const PhaseContext& context() const override { return ctx_; }
  // Stack contacts: clusters of frames lo..m (the driven frame m alone in the last one).
  void set_contacts(ContactLayout layout) {
    layout_ = std::move(layout);
    work_.memo.valid = false;
  }
  ContactWatch calc_contact_watch(const double* q, const double* qdot) const;
  // The mass matrix in the phase's coordinates (diag, sub; the contact impacts).
  void calc_mass(const double* q, const double* qdot, Eigen::VectorXd& diag, Eigen::VectorXd& sub) const;
  PhasePoint calc_point(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override {
    return evaluate(q, qdot, qddot, scratch, PointFields::all);
  }
  // The peaks' part of calc_point (PointFields::loads): all but the kinetic and potential energy.
  PhasePoint calc_loads(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override {
    return evaluate(q, qdot, qddot, scratch, PointFields::loads);
  }
  // Time stepping's part of calc_point: the accelerations and the drive power F y_m'.
  double calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& scratch) const override;
  double calc_driven_speed_m_per_s(const double*, const double* qdot) const override { return qdot[dof() - 1]; }
  // Deployment: rail entry (f falls to 0). Retraction: the driven frame back down at ctx.q_end.
  double calc_end_gap(const double* q) const override {
    return ctx_.direction > 0 ? -calc_rail_function_m(q) : ctx_.q_end - q[dof() - 1];
  }
  // Used by the solver's start check only (can the drive move the mast from rest?): the driven
  // frame's acceleration along the drive's direction.
  double calc_end_gap_acceleration(const double* qddot) const override { return ctx_.direction * qddot[dof() - 1]; }
  void snap_to_end(double* q) const override {  // deployment: the event is located to the event tolerance
    if (ctx_.direction < 0) q[dof() - 1] = ctx_.q_end;
  }
  enum StopEvent { past_miss_height, deploying_straight, singular_bay, above_rail_top, contact_landing, contact_lift_off };
  // A bay within this fraction of l_s of straight (hinge offset) is straight (docs/model.md §2: 1e-4 l_s).
  static constexpr double kStraightFraction = 1e-4;
  void set_watch_rail_top(bool watch) { watch_rail_top_ = watch; }
  int num_stop_events() const override { return layout_.enabled ? 6 : 4; }
  bool is_singular_stop(int k) const override { return k == deploying_straight || k == singular_bay; }
  void calc_stop_events(const double* q, const double* qdot, double* g) const override;
  int num_touches() const override { return rail_touch() + ctx_.bay - std::max(lo_, 1) + 1; }
  void calc_touches(const double* q, const double* qdot, double* h, double* rate) const override;
  int find_touch_event(int k) const override {
    return k < rail_touch() ? -1 : k == num_touches() - 1 ? deploying_straight : singular_bay;
  }
  // Touches h = kStraightFraction l_i - x_i (rate D_i D_i') of bays first_bay..last_bay from the frame
  // heights and velocities ys, vs of frames first.. (phases A and B).
  static void calc_bay_touches(const model::MastParams& mast, int first_bay, int last_bay, const double* ys,
                               const double* vs, int first, double* h, double* rate);
  // Whether bays first_bay..last_bay are all short of straight, |D_i| < 2 l_i, from the frame heights
  // ys of frames first.. (phases A and B): where the equations hold (G(D) > 0, a positive definite
  // mass matrix); the residual form refuses other states.
  static bool are_short_of_straight(const model::MastParams& mast, int first_bay, int last_bay, const double* ys, int first);
  // Rail function of the hinge of bay m (m); > 0 before the pin reaches the rail.
  double calc_rail_function_m(const double* q) const;
  // At a rail entry: its margin (model/rail.hpp, calc_rail_entry_margin_m), from the dip of the
  // uncaptured pin below the rail line and the slack of bay m's diagonals, given the state and its
  // accelerations qddot (calc_point). NaN in the stage of bay 1: frame 0 is held, as in the held
  // stack, and the pin always meets the rail (docs/model-notes.md "Rail margin").
  double calc_rail_entry_margin_m(const double* q, const double* qdot, const double* qddot) const;
  int get_lowest_frame() const { return lo_; }
  // Residual form (phase.hpp): velocity mode one multiplier (the drive force, y_m'' = 0), else none.
  int num_multipliers() const override { return ctx_.drive.mode == model::DriveMode::velocity ? 1 : 0; }
  bool calc_dae_terms(const double* q, const double* qdot, PhaseScratch& scratch, PhaseDaeTerms& out) const override;
  bool calc_frame_heights(const double* q, double* y) const override;
  // Per coordinate (a cluster of frames lo..m), the smallest distance to straight, 2 l_i - |D_i|, of
  // the bays it opens (the one below its lowest frame and the one above its highest).
  bool calc_smooth_lengths(const double* q, double* len) const override;
  // The same for the clusters of frames lo..lo + layout.frames - 1, over the bays up to last_bay,
  // from the frame heights ys of frames first.. (phases A and B).
  static void calc_straight_distances(const model::MastParams& mast, const ContactLayout& layout, int lo, int last_bay,
                                      const double* ys, int first, double* len);
  // Per coordinate (PhaseModel::calc_error_factors), the smallest over the bays it opens (as
  // calc_straight_distances) of min(1, |dD/dx|) = min(1, 4 x / |D|): a height error dy moves the
  // bay's hinge offset x by dy |D| / (4 x), so a tolerance on x is one on the height times 4 x / |D|.
  static void calc_hinge_factors(const model::MastParams& mast, const ContactLayout& layout, int lo, int last_bay,
                                 const double* ys, int first, double* f);
  bool calc_error_factors(const double* q, double* f) const override;
  // Frames above the driven frame m are locked, rigid with it: y_k = y_{k-1} + 2 l_k, k = m+1..n.
  static void fill_locked_heights(const model::MastParams& mast, int m, double* y);
  // The point's kinetic energy (from the phase's mass matrix diag, sub), and the potential energy,
  // smallest opening and largest diagonal tension of the moving bays max(lo, 1)..m (ys: heights of
  // frames first..m; bays: the bay constants); PointFields::loads: the opening and the tension
  // alone. One computation for phases A and B, so that the energy ledger and the peaks see the
  // same quantities on either side of rail entry.
  static void fill_bay_energies(const model::BayConstants* bays, int lo, int m, const double* ys, int first,
                                const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const double* qdot, PhasePoint& p,
                                PointFields fields = PointFields::all);

 private:
  PhaseContext ctx_;
  model::ActiveFrames active_;
  int lo_;
  double held_height_m_;
  bool watch_rail_top_ = false;
  ContactLayout layout_;
  model::RailConstants rail_;   // cot(beta), y_r, 3 sin(beta) of the phase's rail
  mutable FreePhaseWork work_;  // scratch of the evaluations (free_phase_work.hpp)
  // The system of calc_point at (q, q') solved: accelerations into qddot; its mass matrix (reduced
  // to the clusters with stack contacts) and the frame heights point_ys stay in work_.
  struct Motion {
    const Eigen::VectorXd* diag;
    const Eigen::VectorXd* sub;
    double drive_force_N;
  };
  Motion solve_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const;
  PhasePoint evaluate(const double* q, const double* qdot, double* qddot, PhaseScratch& sys, PointFields fields) const;
  int rail_touch() const { return ctx_.direction > 0 ? 1 : 0; }  // deployment: the rail is a touch
  // Frame heights and velocities from frame max(lo - 1, 0) to m (the held frame lo - 1 included).
  void expand_frames(const double* q, const double* qdot, std::vector<double>& ys, std::vector<double>& vs) const;
  // The frames' heights at q (expand_frames at rest; into the work space, valid until its next use).
  const double* calc_frame_heights(const double* q) const;
};

}  // namespace truss::stages
