#include "free_stack/free_phase.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "model/bay.hpp"
#include "model/contacts.hpp"
#include "model/rail.hpp"
#include "model/static_resistance.hpp"

namespace truss::stages {

using namespace truss::model;

FreePhaseA::FreePhaseA(const PhaseContext& ctx, int lo, double held_height_m, const std::vector<BayConstants>& bays)
    : ctx_(ctx), lo_(lo), held_height_m_(held_height_m), rail_(calc_rail_constants(ctx.mast->rail)) {
  if (bays.size() != static_cast<std::size_t>(ctx.mast->n_bays() + 1))
    throw std::invalid_argument("FreePhaseA: the bay table is not the mast's (calc_bay_table)");
  active_.bays = bays.data();
  active_.lo = lo;
  active_.m = ctx.bay;
  active_.locked_mass_kg = ctx.locked_mass_kg;
  active_.panel_height_offset_m = ctx.panel_height_offset_m;
  layout_.frames = ctx.bay - lo + 1;
  work_.memo.keep_system = true;  // calc_point reads the mass matrix from the frame-level system
}

void FreePhaseA::expand_frames(const double* q, const double* qdot, std::vector<double>& ys, std::vector<double>& vs) const {
  const int first = std::max(lo_ - 1, 0), off = lo_ - first;
  ys.resize(static_cast<std::size_t>(ctx_.bay - first + 1));
  vs.resize(ys.size());
  if (off > 0) { ys[0] = held_height_m_; vs[0] = 0.0; }  // frame lo - 1, held
  layout_.expand(q, ys.data() + off);
  layout_.expand(qdot, vs.data() + off);
}

void FreePhaseA::calc_mass(const double* q, const double* qdot, Eigen::VectorXd& diag, Eigen::VectorXd& sub) const {
  std::vector<double> ys, vs;
  expand_frames(q, qdot, ys, vs);
  PhaseScratch sys;
  calc_frame_system(*ctx_.mast, active_, ys.data(), vs.data(), std::max(lo_ - 1, 0), sys);
  Eigen::VectorXd r;
  if (layout_.reduces()) model::reduce_to_clusters(sys.diag, sys.sub, sys.spring_forces, layout_.starts, diag, sub, r);
  else { diag = sys.diag; sub = sys.sub; }
}

ContactWatch FreePhaseA::calc_contact_watch(const double* q, const double* qdot) const {
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  return stages::calc_contact_watch(*this, layout_, lo_, q, qdot, ys.data(), vs.data(), work_.contact);
}

double FreePhaseA::calc_rail_function_m(const double* q) const {
  const int n = dof();
  const double y_m = q[n - 1], y_l = n >= 2 ? q[n - 2] : held_height_m_;
  const double x = calc_hinge_offset_m(ctx_.mast->bay(ctx_.bay), y_m - y_l);
  return model::calc_rail_function_m(ctx_.mast->rail, rail_, x, 0.5 * (y_m + y_l));
}

double FreePhaseA::calc_rail_entry_margin_m(const double* q, const double* qdot, const double* qddot) const {
  const int n = dof(), m = ctx_.bay;
  if (m == 1) return std::numeric_limits<double>::quiet_NaN();  // frame 0 held: the held stack's stage, no miss
  const bool lower_moves = n >= 2;  // else frame m - 1 rests on the stack (stack contacts)
  const double y_lo = lower_moves ? q[n - 2] : held_height_m_;
  const BayParams& b = ctx_.mast->bay(m);
  const double dip = calc_rail_entry_dip_m(ctx_.mast->rail, b.strut_length_m, q[n - 1], y_lo, qdot[n - 1],
                                           lower_moves ? qdot[n - 2] : 0.0, qddot[n - 1], lower_moves ? qddot[n - 2] : 0.0);
  const double b2 = calc_diagonal_offset_sq_m2(ctx_.mast->frame(m - 1), ctx_.mast->frame(m));
  return model::calc_rail_entry_margin_m(dip, b.diagonal_free_length_m - calc_diagonal_length_m(b2, q[n - 1] - y_lo));
}

void FreePhaseA::calc_stop_events(const double* q, const double* qdot, double* g) const {
  const MastParams& mast = *ctx_.mast;
  const int n = dof(), m = ctx_.bay;
  const double l = mast.bay(m).strut_length_m, yr = rail_.axis_height_m;
  const double y_m = q[n - 1], y_l = n >= 2 ? q[n - 2] : held_height_m_;
  g[past_miss_height] = y_m - (yr + 3.0 * l);
  g[deploying_straight] = kStraightFraction * l - calc_hinge_offset_m(mast.bay(m), y_m - y_l);
  double worst = -kStraightFraction * l;  // no bay below m moves: never fires
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  const int first = std::max(lo_ - 1, 0);
  for (int i = std::max(lo_, 1); i < m; ++i) {
    const BayParams& b = mast.bay(i);
    worst = std::max(worst, kStraightFraction * b.strut_length_m - calc_hinge_offset_m(b, ys[i - first] - ys[i - 1 - first]));
  }
  g[singular_bay] = worst;
  if (layout_.enabled) {
    const ContactWatch c = calc_contact_watch(q, qdot);
    g[contact_landing] = c.landing_g;
    g[contact_lift_off] = c.lift_off_g;
  }
  g[above_rail_top] = watch_rail_top_ ? 0.5 * (y_m + y_l) - yr : -1.0;
}

void FreePhaseA::calc_bay_touches(const MastParams& mast, int first_bay, int last_bay, const double* ys, const double* vs,
                                  int first, double* h, double* rate) {
  for (int i = first_bay; i <= last_bay; ++i) {
    const BayParams& b = mast.bay(i);
    const double D = ys[i - first] - ys[i - 1 - first], Dd = vs[i - first] - vs[i - 1 - first];
    *h++ = kStraightFraction * b.strut_length_m - calc_hinge_offset_m(b, D);
    *rate++ = D * Dd;  // dx/dt = -D D' / (4 x)
  }
}

bool FreePhaseA::are_short_of_straight(const MastParams& mast, int first_bay, int last_bay, const double* ys, int first) {
  for (int i = first_bay; i <= last_bay; ++i)
    if (!(std::abs(ys[i - first] - ys[i - 1 - first]) < 2.0 * mast.bay(i).strut_length_m)) return false;
  return true;
}

namespace {

// Per coordinate (a cluster of frames lo..lo + layout.frames - 1), the smallest of per_bay(i) over
// the moving bays i in [max(lo, 1), last_bay] it opens: the one below its lowest frame and the one
// above its highest (+inf where it opens none).
template <class PerBay>
void calc_cluster_minima(const ContactLayout& layout, int lo, int last_bay, PerBay per_bay, double* out) {
  auto bay = [&](int i) { return i < std::max(lo, 1) || i > last_bay ? std::numeric_limits<double>::infinity() : per_bay(i); };
  const int clusters = layout.clusters();
  for (int c = 0; c < clusters; ++c) {
    const int bottom = layout.enabled ? layout.starts[static_cast<std::size_t>(c)] : c;
    const int top = layout.enabled ? (c + 1 < clusters ? layout.starts[static_cast<std::size_t>(c + 1)] : layout.frames) - 1 : c;
    out[c] = std::min(bay(lo + bottom), bay(lo + top + 1));
  }
}

}  // namespace

void FreePhaseA::calc_straight_distances(const MastParams& mast, const ContactLayout& layout, int lo, int last_bay,
                                         const double* ys, int first, double* len) {
  calc_cluster_minima(layout, lo, last_bay, [&](int i) {
    return 2.0 * mast.bay(i).strut_length_m - std::abs(ys[i - first] - ys[i - 1 - first]);
  }, len);
}

void FreePhaseA::calc_hinge_factors(const MastParams& mast, const ContactLayout& layout, int lo, int last_bay,
                                    const double* ys, int first, double* f) {
  calc_cluster_minima(layout, lo, last_bay, [&](int i) {
    const double D = std::abs(ys[i - first] - ys[i - 1 - first]);
    return 4.0 * calc_hinge_offset_m(mast.bay(i), D) / D;  // +inf at D = 0
  }, f);
  for (int c = 0; c < layout.clusters(); ++c) f[c] = std::min(f[c], 1.0);
}

const double* FreePhaseA::calc_frame_heights(const double* q) const {
  std::vector<double>& zero = work_.zero;
  zero.assign(static_cast<std::size_t>(dof()), 0.0);
  expand_frames(q, zero.data(), work_.ys, work_.vs);
  return work_.ys.data();
}

bool FreePhaseA::calc_smooth_lengths(const double* q, double* len) const {
  calc_straight_distances(*ctx_.mast, layout_, lo_, ctx_.bay, calc_frame_heights(q), std::max(lo_ - 1, 0), len);
  return true;
}

bool FreePhaseA::calc_error_factors(const double* q, double* f) const {
  calc_hinge_factors(*ctx_.mast, layout_, lo_, ctx_.bay, calc_frame_heights(q), std::max(lo_ - 1, 0), f);
  return true;
}

void FreePhaseA::calc_touches(const double* q, const double* qdot, double* h, double* rate) const {
  const int n = dof(), m = ctx_.bay;
  std::vector<double>&ys = work_.ys, &vs = work_.vs;
  expand_frames(q, qdot, ys, vs);
  if (rail_touch()) {  // h = -f, f' = (u + w)/2 + c x' with x' = -D (u - w) / (4 x)
    const double u = qdot[n - 1], w = n >= 2 ? qdot[n - 2] : 0.0, D = ys.back() - ys[ys.size() - 2];
    const double x = std::max(calc_hinge_offset_m(ctx_.mast->bay(m), D), kStraightFraction * ctx_.mast->bay(m).strut_length_m);
    *h++ = -calc_rail_function_m(q);
    *rate++ = rail_.cot_beta * D * (u - w) / (4.0 * x) - 0.5 * (u + w);
  }
  calc_bay_touches(*ctx_.mast, std::max(lo_, 1), m, ys.data(), vs.data(), std::max(lo_ - 1, 0), h, rate);
}

bool FreePhaseA::calc_dae_terms(const double* q, const double* qdot, PhaseScratch& sys, PhaseDaeTerms& t) const {
  work_.memo.valid = false;  // point_ys is rewritten
  std::vector<double>&ys = work_.point_ys, &vs = work_.point_vs;
  expand_frames(q, qdot, ys, vs);
  if (!are_short_of_straight(*ctx_.mast, std::max(lo_, 1), ctx_.bay, ys.data(), std::max(lo_ - 1, 0))) return false;
  calc_frame_system(*ctx_.mast, active_, ys.data(), vs.data(), std::max(lo_ - 1, 0), sys);
  const int n = dof();
  t.rhs = sys.velocity_terms + sys.spring_forces;
  if (layout_.reduces()) {  // stack contacts: the clusters' system, as calc_point solves it
    const Eigen::VectorXd r0 = t.rhs;
    model::reduce_to_clusters(sys.diag, sys.sub, r0, layout_.starts, t.diag, t.sub, t.rhs);
  } else {
    t.diag = sys.diag;
    t.sub = sys.sub;
  }
  t.driven_speed_m_per_s = qdot[n - 1];
  t.num_multipliers = num_multipliers();
  if (ctx_.drive.mode == DriveMode::velocity) {
    // y_m'' = 0 with the drive force as its multiplier (M y'' = r + F e_m).
    t.c[0] = Eigen::VectorXd::Unit(n, n - 1);
    t.s[0] = 0.0;
    t.drive_multiplier = 0;
    return true;
  }
  t.drive_multiplier = -1;
  t.drive_force_N = ctx_.drive.calc_force_N(qdot[n - 1], ctx_.direction);
  t.rhs[n - 1] += t.drive_force_N;
  return true;
}

void FreePhaseA::fill_bay_energies(const BayConstants* bays, int lo, int m, const double* ys, int first, const Eigen::VectorXd& diag,
                                   const Eigen::VectorXd& sub, const double* qdot, PhasePoint& p, PointFields fields) {
  const bool energies = fields == PointFields::all;
  double T = 0.0, U = 0.0, tension = 0.0;
  for (Eigen::Index k = 0; energies && k < diag.size(); ++k) {
    T += 0.5 * diag[k] * qdot[k] * qdot[k];
    if (k > 0) T += sub[k] * qdot[k] * qdot[k - 1];
  }
  for (int i = std::max(lo, 1); i <= m; ++i) {
    const DiagonalConstants& c = bays[i].diagonals;
    const double Di = ys[i - first] - ys[i - 1 - first];
    if (energies) U += calc_bay_potential_J(c, Di);
    p.min_bay_opening_m = std::min(p.min_bay_opening_m, Di);
    tension = std::max(tension, calc_diagonal_tension_N(c, Di));
  }
  p.kinetic_energy_J = T;
  p.potential_energy_J = U;
  p.diagonal_tension_N = tension;
}

void FreePhaseA::fill_locked_heights(const MastParams& mast, int m, double* y) {
  for (int k = m + 1; k <= mast.n_bays(); ++k) y[k] = y[k - 1] + 2.0 * mast.bay(k).strut_length_m;
}

bool FreePhaseA::calc_frame_heights(const double* q, double* y) const {
  const int m = ctx_.bay, first = std::max(lo_ - 1, 0);
  std::vector<double>&ys = work_.ys, &vs = work_.vs, &zero = work_.zero;
  zero.assign(static_cast<std::size_t>(dof()), 0.0);
  expand_frames(q, zero.data(), ys, vs);  // frames first..m, clusters expanded
  for (int k = 0; k < first; ++k) y[k] = held_height_m_;
  for (int k = first; k <= m; ++k) y[k] = ys[static_cast<std::size_t>(k - first)];
  fill_locked_heights(*ctx_.mast, m, y);
  return true;
}

FreePhaseA::Motion FreePhaseA::solve_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const {
  const int n = dof();
  FreePhaseWork& w = work_;
  const bool reduce = layout_.reduces();
  if (w.memo.matches(q, qdot, n)) {  // the work space still holds this state's solve
    w.memo.restore_system(sys);
    for (int k = 0; k < n; ++k) qddot[k] = w.memo.qddot[static_cast<std::size_t>(k)];
    return Motion{reduce ? &w.diag : &sys.diag, reduce ? &w.sub : &sys.sub, w.memo.drive_force_N};
  }
  w.memo.valid = false;
  // Heights and velocities from frame lo - 1 (held) when it exists, so that bay lo sees it.
  expand_frames(q, qdot, w.point_ys, w.point_vs);
  calc_frame_system(*ctx_.mast, active_, w.point_ys.data(), w.point_vs.data(), std::max(lo_ - 1, 0), sys);
  w.rhs = sys.velocity_terms + sys.spring_forces;
  // Stack contacts: frames in closed contact move as clusters (model/contacts.hpp).
  if (reduce) model::reduce_to_clusters(sys.diag, sys.sub, w.rhs, layout_.starts, w.diag, w.sub, w.rhs_reduced);
  const Eigen::VectorXd& Md = reduce ? w.diag : sys.diag;
  const Eigen::VectorXd& Ms = reduce ? w.sub : sys.sub;
  Eigen::VectorXd& rhs = reduce ? w.rhs_reduced : w.rhs;
  Motion out{&Md, &Ms, 0.0};
  // A mass matrix that is not positive definite (a bay past straight inside a trial step) gives
  // NaN accelerations: the integrator rejects the step and the stop events end the phase.
  bool solved = true;
  if (ctx_.drive.mode == DriveMode::velocity) {
    for (int k = 0; k < n; ++k) qddot[k] = 0.0;
    if (n > 1) {
      solved = solve_tridiagonal(Md.head(n - 1), Ms.head(n - 1), rhs.head(n - 1), w.acc, w.solve);
      if (solved) for (int k = 0; k + 1 < n; ++k) qddot[k] = w.acc[k];
    }
    out.drive_force_N = (n > 1 ? Ms[n - 1] * qddot[n - 2] : 0.0) - rhs[n - 1];
  } else {
    out.drive_force_N = ctx_.drive.calc_force_N(qdot[n - 1], ctx_.direction);
    rhs[n - 1] += out.drive_force_N;
    solved = solve_tridiagonal(Md, Ms, rhs, w.acc, w.solve);
    if (solved) for (int k = 0; k < n; ++k) qddot[k] = w.acc[k];
  }
  if (!solved) {
    for (int k = 0; k < n; ++k) qddot[k] = std::numeric_limits<double>::quiet_NaN();
    out.drive_force_N = qddot[0];
    return out;
  }
  w.memo.store(q, qdot, qddot, n, sys);
  w.memo.drive_force_N = out.drive_force_N;
  return out;
}

double FreePhaseA::calc_motion(const double* q, const double* qdot, double* qddot, PhaseScratch& sys) const {
  return solve_motion(q, qdot, qddot, sys).drive_force_N * qdot[dof() - 1];
}

PhasePoint FreePhaseA::evaluate(const double* q, const double* qdot, double* qddot, PhaseScratch& sys, PointFields fields) const {
  const MastParams& mast = *ctx_.mast;
  const int n = dof(), m = ctx_.bay;
  const Motion mo = solve_motion(q, qdot, qddot, sys);
  PhasePoint p;
  p.drive_force_N = mo.drive_force_N;
  const double u = qdot[n - 1];
  p.q = q[n - 1]; p.qdot = u; p.qddot = qddot[n - 1];
  p.y_driven_m = q[n - 1];
  p.y_lower_m = n >= 2 ? q[n - 2] : held_height_m_;
  p.u_m_per_s = u;
  p.w_m_per_s = n >= 2 ? qdot[n - 2] : 0.0;
  const double D = p.y_driven_m - p.y_lower_m;
  p.hinge_x_m = calc_hinge_offset_m(mast.bay(m), D);
  p.hinge_y_m = 0.5 * (p.y_driven_m + p.y_lower_m);
  p.rail_distance_m = model::calc_rail_function_m(mast.rail, rail_, p.hinge_x_m, p.hinge_y_m) * std::sin(mast.rail.beta_rad);
  fill_bay_energies(active_.bays, lo_, m, work_.point_ys.data(), std::max(lo_ - 1, 0), *mo.diag, *mo.sub, qdot, p, fields);
  p.static_drive_force_N = model::calc_open_static_drive_force_N(-sys.spring_forces[sys.spring_forces.size() - 1]);
  p.mass_yy = (*mo.diag)[n - 1];
  return p;
}

}  // namespace truss::stages
