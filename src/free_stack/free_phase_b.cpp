#include "free_stack/free_phase_b.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "model/bay.hpp"
#include "model/contacts.hpp"
#include "model/rail.hpp"
#include "model/static_resistance.hpp"
#include "free_stack/free_phase.hpp"

namespace truss::stages {

using namespace truss::model;

FreePhaseB::FreePhaseB(const PhaseContext& ctx, int lo, double held_height_m, double alpha_per_s,
                       const std::vector<BayConstants>& bays)
    : ctx_(ctx), lo_(lo), held_height_m_(held_height_m), alpha_(alpha_per_s), rail_(calc_rail_constants(ctx.mast->rail)) {
  if (bays.size() != static_cast<std::size_t>(ctx.mast->n_bays() + 1))
    throw std::invalid_argument("FreePhaseB: the bay table is not the mast's (calc_bay_table)");
  active_.bays = bays.data();
  active_.lo = lo;
  active_.m = ctx.bay;
  active_.bay_m_in_hinge_coordinate = true;
  active_.locked_mass_kg = ctx.locked_mass_kg;
  active_.panel_height_offset_m = ctx.panel_height_offset_m;
  layout_.frames = ctx.bay - lo;
  chain_slack_span_m_ = calc_chain_slack_span_m(*ctx.mast, 1, ctx.bay - 1);
}

void FreePhaseB::expand_frames(const double* q, const double* qdot, std::vector<double>& ys, std::vector<double>& vs) const {
  const int n = dof(), m = ctx_.bay, first = std::max(lo_ - 1, 0), off = lo_ - first;
  ys.resize(static_cast<std::size_t>(m - first + 1));
  vs.resize(ys.size());
  if (off > 0) { ys[0] = held_height_m_; vs[0] = 0.0; }  // frame lo - 1, held
  layout_.expand(q, ys.data() + off);
  layout_.expand(qdot, vs.data() + off);
  const double x = q[n - 1], l = ctx_.mast->bay(m).strut_length_m, s = std::sqrt(l * l - x * x);
  ys.back() = q[n - 2] + 2.0 * s;
  vs.back() = qdot[n - 2] - 2.0 * x / s * qdot[n - 1];
}

void FreePhaseB::calc_mass(const double* q, const double* qdot, Eigen::VectorXd& diag, Eigen::VectorXd& sub) const {
  std::vector<double> acc(static_cast<std::size_t>(dof()));
  PhaseScratch sys;
  const PhasePoint p = evaluate(q, qdot, acc.data(), sys, &diag, &sub, PointFields::loads);
  (void)p;
}

ContactWatch FreePhaseB::calc_contact_watch(const double* q, const double* qdot) const {
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  return stages::calc_contact_watch(*this, layout_, lo_, q, qdot, ys.data(), vs.data(), work_.contact);
}

double FreePhaseB::calc_rail_function_m(const double* q) const {
  const int n = dof();
  const double x = q[n - 1];
  const double l = ctx_.mast->bay(ctx_.bay).strut_length_m;
  const double s = std::sqrt(l * l - x * x);
  return q[n - 2 >= 0 ? n - 2 : 0] + s - rail_.axis_height_m + rail_.cot_beta * x;
}

void FreePhaseB::calc_stop_events(const double* q, const double* qdot, double* g) const {
  const MastParams& mast = *ctx_.mast;
  double worst = -FreePhaseA::kStraightFraction * mast.bay(ctx_.bay).strut_length_m;  // none: never fires
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  const int first = std::max(lo_ - 1, 0);
  for (int i = std::max(lo_, 1); i < ctx_.bay; ++i) {
    const BayParams& b = mast.bay(i);
    worst = std::max(worst, FreePhaseA::kStraightFraction * b.strut_length_m - calc_hinge_offset_m(b, ys[i - first] - ys[i - 1 - first]));
  }
  g[0] = worst;
  if (layout_.enabled) {
    const ContactWatch c = calc_contact_watch(q, qdot);
    g[1] = c.landing_g;
    g[2] = c.lift_off_g;
  }
}

void FreePhaseB::calc_touches(const double* q, const double* qdot, double* h, double* rate) const {
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  FreePhaseA::calc_bay_touches(*ctx_.mast, std::max(lo_, 1), ctx_.bay - 1, ys.data(), vs.data(), std::max(lo_ - 1, 0), h, rate);
}

double FreePhaseB::calc_driven_speed_m_per_s(const double* q, const double* qdot) const {
  const int n = dof();
  const double x = q[n - 1], l = ctx_.mast->bay(ctx_.bay).strut_length_m;
  return qdot[n - 2] - 2.0 * x / std::sqrt(l * l - x * x) * qdot[n - 1];
}

// The bordered system's terms at (q, q') (the header's equations; with stack contacts the frame
// system reduced to the clusters first), with the frame heights first..m into ys, vs.
bool FreePhaseB::assemble(const double* q, const double* qdot, PhaseScratch& sys, std::vector<double>& ys,
                          std::vector<double>& vs, PhaseDaeTerms& t) const {
  const MastParams& mast = *ctx_.mast;
  const int n = dof(), m = ctx_.bay;
  const BayParams& bay = mast.bay(m);
  const double l = bay.strut_length_m, c = rail_.cot_beta;
  const double x = q[n - 1], xi = qdot[n - 1], xi2 = xi * xi;
  const double s = std::sqrt(l * l - x * x), k = 2.0 * x / s, kx = 2.0 * l * l / (s * s * s);
  // Frame heights first..m (frame lo - 1 held when it exists).
  const int first = std::max(lo_ - 1, 0);
  expand_frames(q, qdot, ys, vs);
  const double y_l = q[n - 2], u = vs.back();
  calc_frame_system(mast, active_, ys.data(), vs.data(), first, sys);
  t.diag = sys.diag;
  t.sub = sys.sub;
  t.rhs = sys.velocity_terms + sys.spring_forces;
  if (layout_.reduces()) {
    // Stack contacts: clusters of frames lo..m-1, frame m alone (model/contacts.hpp).
    std::vector<int> starts = layout_.starts;
    starts.push_back(layout_.frames);
    const Eigen::VectorXd r0 = t.rhs;
    model::reduce_to_clusters(sys.diag, sys.sub, r0, starts, t.diag, t.sub, t.rhs);
  }
  const double A_ll = t.diag[n - 2], A_ml = t.sub[n - 1], A_mm = t.diag[n - 1];
  const double R_l = t.rhs[n - 2], R_m = t.rhs[n - 1];
  const double g = calc_g_hinge(bay, x), dg = calc_dg_hinge_dx(bay, x), h = -kx * xi2;
  t.diag[n - 2] = A_ll + 2.0 * A_ml + A_mm;
  t.sub[n - 1] = -k * (A_ml + A_mm);
  t.diag[n - 1] = k * k * A_mm + 2.0 * g;
  t.rhs[n - 2] = R_l + R_m - (A_ml + A_mm) * h;
  t.rhs[n - 1] = -k * (R_m - A_mm * h) - dg * xi2;
  // a and b are zero but on the last two rows (written here, the other rows only by the resize).
  Eigen::VectorXd& a = t.c[0];
  Eigen::VectorXd& b = t.c[1];
  if (a.size() != n || b.size() != n) { a.setZero(n); b.setZero(n); }
  a[n - 2] = 1.0; a[n - 1] = c - x / s;
  b[n - 2] = 1.0; b[n - 1] = -k;
  const double f = y_l + s - rail_.axis_height_m + c * x, fdot = qdot[n - 2] + a[n - 1] * qdot[n - 1];  // f' = a . dq/dt
  t.s[0] = l * l / (s * s * s) * xi2 - 2.0 * alpha_ * fdot - alpha_ * alpha_ * f;
  t.driven_speed_m_per_s = u;
  t.num_multipliers = num_multipliers();
  if (ctx_.drive.mode == DriveMode::velocity) {
    // The second row y_m'' = 0 (drive force as its multiplier), with the speed's Baumgarte term.
    t.s[1] = kx * xi2 - alpha_ * (u - ctx_.direction * ctx_.drive.speed_m_per_s);
    t.drive_multiplier = 1;
  } else {
    t.drive_multiplier = -1;
    t.drive_force_N = ctx_.drive.calc_force_N(u, ctx_.direction);
    t.rhs += t.drive_force_N * b;
  }
  return std::isfinite(s);
}

bool FreePhaseB::calc_dae_terms(const double* q, const double* qdot, PhaseScratch& sys, PhaseDaeTerms& t) const {
  work_.memo.valid = false;  // point_ys is rewritten
  return assemble(q, qdot, sys, work_.point_ys, work_.point_vs, t) &&
         FreePhaseA::are_short_of_straight(*ctx_.mast, std::max(lo_, 1), ctx_.bay - 1, work_.point_ys.data(), std::max(lo_ - 1, 0));
}

bool FreePhaseB::calc_frame_heights(const double* q, double* y) const {
  const int m = ctx_.bay, first = std::max(lo_ - 1, 0);
  std::vector<double>&ys = work_.ys, &vs = work_.vs, &zero = work_.zero;
  zero.assign(static_cast<std::size_t>(dof()), 0.0);
  expand_frames(q, zero.data(), ys, vs);  // frames first..m, clusters expanded, frame m from x
  for (int k = 0; k < first; ++k) y[k] = held_height_m_;
  for (int k = first; k <= m; ++k) y[k] = ys[static_cast<std::size_t>(k - first)];
  FreePhaseA::fill_locked_heights(*ctx_.mast, m, y);
  return true;
}

bool FreePhaseB::calc_smooth_lengths(const double* q, double* len) const {
  std::vector<double>&ys = work_.ys, &vs = work_.vs, &zero = work_.zero;
  zero.assign(static_cast<std::size_t>(dof()), 0.0);
  expand_frames(q, zero.data(), ys, vs);
  FreePhaseA::calc_straight_distances(*ctx_.mast, layout_, lo_, ctx_.bay - 1, ys.data(), std::max(lo_ - 1, 0), len);
  len[dof() - 1] = std::numeric_limits<double>::infinity();
  return true;
}

bool FreePhaseB::calc_error_factors(const double* q, double* f) const {
  std::vector<double>&ys = work_.ys, &vs = work_.vs, &zero = work_.zero;
  zero.assign(static_cast<std::size_t>(dof()), 0.0);
  expand_frames(q, zero.data(), ys, vs);
  FreePhaseA::calc_hinge_factors(*ctx_.mast, layout_, lo_, ctx_.bay - 1, ys.data(), std::max(lo_ - 1, 0), f);
  f[dof() - 1] = 1.0;
  return true;
}

FreePhaseB::Motion FreePhaseB::solve_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const {
  const int n = dof();
  FreePhaseWork& w = work_;
  PhaseDaeTerms& t = w.terms;
  if (w.memo.matches(q, qdot, n)) {  // the work space still holds this state's solve
    w.memo.restore_system(sys);
    for (int i = 0; i < n; ++i) qddot[i] = w.memo.qddot[static_cast<std::size_t>(i)];
    return Motion{w.memo.drive_force_N, w.memo.lambda_N};
  }
  w.memo.valid = false;
  assemble(q, qdot, sys, w.point_ys, w.point_vs, t);
  // The rail row (and in velocity mode the row y_m'' = 0, the drive force as its multiplier); a
  // and b are zero but on the last two coordinates (model/tridiagonal.hpp, solve_tail_constrained).
  const int k = ctx_.drive.mode == DriveMode::velocity ? 2 : 1;
  double mu[2] = {0.0, 0.0};
  Motion out{t.drive_force_N, 0.0};
  const bool solved = solve_tail_constrained(t.diag, t.sub, t.rhs, t.c, k, t.s, w.acc, mu, w.solve);
  // Not positive definite (a bay past straight inside a trial step): NaN, the step is rejected.
  if (!solved) {
    for (int i = 0; i < n; ++i) qddot[i] = std::numeric_limits<double>::quiet_NaN();
    out.lambda_N = out.drive_force_N = qddot[0];
    return out;
  }
  for (int i = 0; i < n; ++i) qddot[i] = w.acc[i];
  out.lambda_N = mu[0];
  if (k == 2) out.drive_force_N = mu[1];
  w.memo.store(q, qdot, qddot, n, sys);
  w.memo.drive_force_N = out.drive_force_N;
  w.memo.lambda_N = out.lambda_N;
  return out;
}

double FreePhaseB::calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const {
  const Motion mo = solve_motion(q, qdot, qddot, sys);
  return mo.drive_force_N * work_.point_vs.back();
}

PhasePoint FreePhaseB::evaluate(const double* q, const double* qdot, double* qddot, PhaseScratch& sys, Eigen::VectorXd* mass_diag,
                                Eigen::VectorXd* mass_sub, PointFields fields) const {
  const MastParams& mast = *ctx_.mast;
  const int n = dof(), m = ctx_.bay;
  const double l = mast.bay(m).strut_length_m, c = rail_.cot_beta;
  const double x = q[n - 1], xi = qdot[n - 1], s = std::sqrt(l * l - x * x);
  const Motion mo = solve_motion(q, qdot, qddot, sys);
  const PhaseDaeTerms& t = work_.terms;
  if (mass_diag) { *mass_diag = t.diag; *mass_sub = t.sub; }
  const Eigen::VectorXd &diag = t.diag, &sub = t.sub;
  const std::vector<double>&ys = work_.point_ys, &vs = work_.point_vs;
  PhasePoint p;
  p.drive_force_N = mo.drive_force_N;
  p.q = x; p.qdot = xi; p.qddot = qddot[n - 1];
  p.y_driven_m = ys.back(); p.y_lower_m = q[n - 2];
  p.u_m_per_s = vs.back(); p.w_m_per_s = qdot[n - 2];
  p.hinge_x_m = x; p.hinge_y_m = q[n - 2] + s;
  p.lambda_N = mo.lambda_N;
  p.pin_force_N = calc_pin_force_N(rail_, mo.lambda_N);
  p.rail_residual_m = std::abs(calc_rail_function_m(q));
  FreePhaseA::fill_bay_energies(active_.bays, lo_, m, ys.data(), std::max(lo_ - 1, 0), diag, sub, qdot, p, fields);
  p.mass_yy = diag[n - 2]; p.mass_yx = sub[n - 1]; p.mass_xx = diag[n - 1];
  p.rail_slope = c - x / s;
  // At rest with the hinge at x, bays 1..m-1 below frame m-1 pull with their chain's equilibrium tension.
  // The deploying bay's pull U_m'(D_m) from the model, not from the caller's scratch (a memo hit
  // may leave that scratch holding another state's system).
  const double y_l = q[n - 2];
  const double pull = m >= 2 ? calc_chain_pull_N(mast, 1, m - 1, y_l - held_height_m_, chain_slack_span_m_) : 0.0;
  const double bay_pull_N = calc_bay_dU_dD_N(active_.bays[m].diagonals, ys.back() - y_l);
  p.static_drive_force_N = calc_on_rail_static_drive_force_N(c, x / s, bay_pull_N, pull);
  return p;
}

}  // namespace truss::stages
