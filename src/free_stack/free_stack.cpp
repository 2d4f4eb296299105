#include "free_stack/free_stack.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "model/bay.hpp"
#include "model/contacts.hpp"
#include "model/frames.hpp"
#include "model/impacts.hpp"
#include "model/rail.hpp"
#include "free_stack/free_phase.hpp"
#include "free_stack/free_phase_b.hpp"

namespace truss::stages {

using namespace truss::model;

FreeStack::FreeStack(const MastParams& mast, bool contacts)
    : mast_(mast), bays_(calc_bay_table(mast)), contacts_(contacts), y_(static_cast<std::size_t>(mast.n_bays() + 1), 0.0), v_(y_.size(), 0.0),
      closed_(y_.size(), contacts ? 1 : 0) {
  closed_[0] = 0;  // frame 0 has no contact below it (held on the floor)
  block_top_ = contacts ? mast.n_bays() : 0;
}

int FreeStack::calc_lowest_frame(PhaseKind kind, int m) const {
  // Frame 0 is held (lo >= 1) until bay 1's rail lifts it; the rail moves frame m - 1.
  if (kind == PhaseKind::on_rail) return m >= 2 ? std::min(block_top_, m - 2) + 1 : 0;
  return std::min(block_top_, m - 1) + 1;
}

ContactLayout FreeStack::make_layout(PhaseKind kind, int m, int lo) const {
  ContactLayout L;
  const int top = kind == PhaseKind::open ? m : m - 1;
  L.frames = top - lo + 1;
  L.enabled = contacts_;
  if (!contacts_) return L;
  L.block_liftable = lo - 1 >= 1;
  L.driven_contact = retract_ && kind == PhaseKind::open;
  for (int i = lo; i <= top; ++i)
    if (i == lo || (i == m && !L.driven_contact) || !closed_[static_cast<std::size_t>(i)]) L.starts.push_back(i - lo);
  return L;
}

std::unique_ptr<PhaseModel> FreeStack::make_phase(const PhaseContext& ctx, bool watch_rail_top) const {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay);
  last_lo_ = lo;
  const double held = y_[0];  // frame 0 and the resting block are the only held frames (height 0)
  if (ctx.kind == PhaseKind::open) {
    auto a = std::make_unique<FreePhaseA>(ctx, lo, held, bays_);
    a->set_watch_rail_top(watch_rail_top);
    if (contacts_) a->set_contacts(make_layout(ctx.kind, ctx.bay, lo));
    return a;
  }
  auto b = std::make_unique<FreePhaseB>(ctx, lo, held, kBaumgarteRate_per_s, bays_);
  if (contacts_) b->set_contacts(make_layout(ctx.kind, ctx.bay, lo));
  return b;
}

void FreeStack::get_start(const PhaseContext& ctx, std::vector<double>& q, std::vector<double>& qdot) const {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay), m = ctx.bay;
  const ContactLayout L = make_layout(ctx.kind, m, lo);
  q.clear();
  qdot.clear();
  for (int c = 0; c < L.clusters(); ++c) {
    const int k = lo + (L.enabled ? L.starts[static_cast<std::size_t>(c)] : c);
    q.push_back(y_[static_cast<std::size_t>(k)]);
    qdot.push_back(v_[static_cast<std::size_t>(k)]);
  }
  if (ctx.kind == PhaseKind::on_rail) { q.push_back(x_); qdot.push_back(xi_); }
}

void FreeStack::set_end(const PhaseContext& ctx, const std::vector<double>& st) {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay), m = ctx.bay;
  const ContactLayout L = make_layout(ctx.kind, m, lo);
  const int n = static_cast<int>(st.size()) / 2;
  L.expand(st.data(), y_.data() + lo);
  L.expand(st.data() + n, v_.data() + lo);
  if (ctx.kind == PhaseKind::on_rail) {
    // (.., y_{m-1}, x): y_m = y_{m-1} + 2 s(x), y_m' = y_{m-1}' - (2x/s) x'.
    x_ = st[static_cast<std::size_t>(n - 1)];
    xi_ = st[static_cast<std::size_t>(2 * n - 1)];
    const double l = mast_.bay(m).strut_length_m, s = std::sqrt(std::max(0.0, l * l - x_ * x_));
    y_[static_cast<std::size_t>(m)] = y_[static_cast<std::size_t>(m - 1)] + 2.0 * s;
    v_[static_cast<std::size_t>(m)] = v_[static_cast<std::size_t>(m - 1)] - (s > 0.0 ? 2.0 * x_ / s : 0.0) * xi_;
  }
}

ActiveFrames FreeStack::make_active(const StageSpec& s, int lo) const {
  ActiveFrames a;
  a.lo = lo;
  a.m = s.bay;
  a.locked_mass_kg = s.locked_mass_kg;
  a.panel_height_offset_m = s.panel_height_offset_m;
  a.bays = bays_.data();
  return a;
}

void FreeStack::calc_cluster_system(const StageSpec& s, PhaseKind kind, int lo, FrameSystem& sys, Eigen::VectorXd& v) const {
  const int m = s.bay, first = std::max(lo - 1, 0);
  calc_frame_system(mast_, make_active(s, lo), y_.data() + first, v_.data() + first, first, sys);
  const ContactLayout L = make_layout(kind, m, lo);
  std::vector<int> starts = L.starts;
  if (kind == PhaseKind::on_rail) starts.push_back(m - lo);
  if (!L.enabled || static_cast<int>(starts.size()) == m - lo + 1) {
    v = Eigen::Map<const Eigen::VectorXd>(v_.data() + lo, m - lo + 1);
    return;
  }
  const Eigen::VectorXd d = sys.diag, sb = sys.sub, r = sys.velocity_terms + sys.spring_forces;
  Eigen::VectorXd rc;
  reduce_to_clusters(d, sb, r, starts, sys.diag, sys.sub, rc);
  v.resize(static_cast<Eigen::Index>(starts.size()));
  for (std::size_t c = 0; c < starts.size(); ++c) v[static_cast<Eigen::Index>(c)] = v_[static_cast<std::size_t>(lo + starts[c])];
}

void FreeStack::add_cluster_velocities(const ContactLayout& L, int lo, const Eigen::VectorXd& dv) {
  std::vector<double> dvf(static_cast<std::size_t>(L.frames));
  L.expand(dv.data(), dvf.data());
  for (int k = 0; k < L.frames; ++k) v_[static_cast<std::size_t>(lo + k)] += dvf[static_cast<std::size_t>(k)];
}

StackImpact FreeStack::apply_start_kick(const StageSpec& s, double u) {
  const int lo = calc_lowest_frame(PhaseKind::open, s.bay);
  FrameSystem sys;
  Eigen::VectorXd v;
  calc_cluster_system(s, PhaseKind::open, lo, sys, v);
  TridiagonalWork w;
  StackImpact k = s.start_kick ? calc_stack_start_kick(sys.diag, sys.sub, u, w) : calc_stack_start_rest(sys.diag, u);
  if (k.ok) add_cluster_velocities(make_layout(PhaseKind::open, s.bay, lo), lo, k.dv);
  return k;
}

FreeRailEntry FreeStack::apply_rail_entry(const StageSpec& s, bool drive_holds_speed) {
  const int m = s.bay;
  // Contacts: a lower frame resting on the block leaves it (the rail takes it; checked below).
  const bool from_block = contacts_ && m >= 2 && block_top_ >= m - 1;
  if (from_block) { block_top_ = m - 2; closed_[static_cast<std::size_t>(m - 1)] = 0; }
  const int lo = calc_lowest_frame(PhaseKind::on_rail, m);
  // Bay m in frame heights (regular off the lock), the moving set of phase B (clusters, frame m).
  FrameSystem sys;
  Eigen::VectorXd v;
  calc_cluster_system(s, PhaseKind::on_rail, lo, sys, v);
  const double D = y_[static_cast<std::size_t>(m)] - y_[static_cast<std::size_t>(m - 1)];
  FreeRailEntry r;
  r.hinge_x_m = model::calc_hinge_offset_m(mast_.bay(m), D);
  const Eigen::Vector2d J = calc_rail_gradient(mast_.rail.cot_beta(), D, r.hinge_x_m);
  TridiagonalWork w;
  r.impact = calc_stack_rail_entry(sys.diag, sys.sub, v, J[0], J[1], drive_holds_speed, w);
  if (!r.impact.ok) return r;
  ContactLayout L = make_layout(PhaseKind::on_rail, m, lo);
  L.starts.push_back(m - lo);
  ++L.frames;
  add_cluster_velocities(L, lo, r.impact.dv);
  // With contacts the rail must lift a lower frame that rested on the block (else it would have to
  // push frames into the stack while the rail holds it: no plastic solution of this law).
  if (from_block && v_[static_cast<std::size_t>(m - 1)] < 0.0) r.impact.ok = false;
  // Hinge coordinate: D = 2 s, y_m' - y_{m-1}' = -(2x/s) x'.
  x_ = r.hinge_x_m;
  const double sh = 0.5 * D;
  xi_ = (v_[static_cast<std::size_t>(m - 1)] - v_[static_cast<std::size_t>(m)]) * sh / (2.0 * x_);
  return r;
}

ContactWatch FreeStack::watch_at(const PhaseContext& ctx) const {
  std::vector<double> q, qd;
  get_start(ctx, q, qd);
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay);
  if (ctx.kind == PhaseKind::open) {
    FreePhaseA a(ctx, lo, y_[0], bays_);
    a.set_contacts(make_layout(ctx.kind, ctx.bay, lo));
    return a.calc_contact_watch(q.data(), qd.data());
  }
  FreePhaseB b(ctx, lo, y_[0], kBaumgarteRate_per_s, bays_);
  b.set_contacts(make_layout(ctx.kind, ctx.bay, lo));
  return b.calc_contact_watch(q.data(), qd.data());
}

void FreeStack::open_contact(int j) {
  closed_[static_cast<std::size_t>(j)] = 0;
  if (j <= block_top_) block_top_ = j - 1;
}

FreeSegmentStart FreeStack::prepare_segment(const PhaseContext& ctx, bool drive_holds_speed) {
  FreeSegmentStart p;
  if (!contacts_) return p;
  // Active set: open the most pulling contact and look again (each pass opens one; at most n).
  for (int it = 0; it <= 2 * mast_.n_bays() + 2; ++it) {
    const ContactWatch w = watch_at(ctx);
    if (w.lift_off_g > 0.0) {
      open_contact(w.lift_off_bay);
      ++p.lift_offs;
    } else if (w.touching_bay > 0) {  // touching and closing: it lands now (its crossing began at 0)
      const FreeContactEvent e = land(ctx, w.touching_bay, drive_holds_speed);
      p.energy_loss_J += e.energy_loss_J;
      p.drive_work_J += e.drive_work_J;
      ++p.landings;
      if (!e.ok) { p.ok = false; p.bay = e.bay; break; }
    } else {
      break;
    }
  }
  return p;
}

FreeSegmentStart FreeStack::apply_contact_event(const PhaseContext& ctx, int stop_event, bool drive_holds_speed) {
  FreeSegmentStart r;
  const bool open = ctx.kind == PhaseKind::open;
  const int landing = open ? FreePhaseA::contact_landing : 1, lift = open ? FreePhaseA::contact_lift_off : 2;
  if (!contacts_ || (stop_event != landing && stop_event != lift)) return r;
  r.handled = true;
  const ContactWatch w = watch_at(ctx);
  if (stop_event == lift) {
    open_contact(w.lift_off_bay);
    r.lift_offs = 1;
    return r;
  }
  // The touching, closing contact (several may touch at one event), else the one that crossed.
  const FreeContactEvent e = land(ctx, w.touching_bay > 0 ? w.touching_bay : w.landing_bay, drive_holds_speed);
  r.landings = 1;
  r.energy_loss_J = e.energy_loss_J;
  r.drive_work_J = e.drive_work_J;
  r.ok = e.ok;
  r.bay = e.bay;
  return r;
}

FreeContactEvent FreeStack::land(const PhaseContext& ctx, int bay, bool drive_holds_speed) {
  FreeContactEvent e;
  e.handled = e.landing = true;
  e.bay = bay;
  const bool open = ctx.kind == PhaseKind::open;
  const int m = ctx.bay, lo = calc_lowest_frame(ctx.kind, m);
  const ContactLayout L = make_layout(ctx.kind, m, lo);
  std::vector<double> q, qd;
  get_start(ctx, q, qd);
  const int n = static_cast<int>(q.size());
  int c = 0;
  while (c < static_cast<int>(L.starts.size()) && lo + L.starts[static_cast<std::size_t>(c)] != e.bay) ++c;
  if (c == static_cast<int>(L.starts.size())) { e.ok = false; return e; }  // not an open contact
  Eigen::VectorXd diag, sub;
  if (open) {
    FreePhaseA a(ctx, lo, y_[0], bays_);
    a.set_contacts(L);
    a.calc_mass(q.data(), qd.data(), diag, sub);
  } else {
    FreePhaseB b(ctx, lo, y_[0], kBaumgarteRate_per_s, bays_);
    b.set_contacts(L);
    b.calc_mass(q.data(), qd.data(), diag, sub);
  }
  // Rows: the closing contact (J v+ = 0), the rail (phase B), the screw (velocity drive).
  std::vector<Eigen::VectorXd> rows(1, Eigen::VectorXd::Zero(n));
  rows[0][c] = 1.0;
  if (c > 0) rows[0][c - 1] = -1.0;
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  d[0] = -(qd[static_cast<std::size_t>(c)] - (c > 0 ? qd[static_cast<std::size_t>(c - 1)] : 0.0));
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  if (open) {
    b[n - 1] = 1.0;
  } else {
    const double x = q.back(), l = mast_.bay(m).strut_length_m, sx = std::sqrt(l * l - x * x);
    Eigen::VectorXd a = Eigen::VectorXd::Zero(n);
    a[n - 2] = 1.0; a[n - 1] = mast_.rail.cot_beta() - x / sx;
    b[n - 2] = 1.0; b[n - 1] = -2.0 * x / sx;
    rows.push_back(a);
  }
  if (drive_holds_speed) rows.push_back(b);
  TridiagonalWork wk;
  const ConstrainedImpact imp = calc_constrained_impact(diag, sub, rows, d, wk);
  // A lower frame on the rail landing on the resting block would lock the mechanism: no solution.
  e.ok = imp.ok && !(c == 0 && !open && L.starts.size() == 1);
  if (!e.ok) return e;
  e.energy_loss_J = imp.energy_loss_J;
  const Eigen::Map<const Eigen::VectorXd> v0(qd.data(), n);
  if (drive_holds_speed) e.drive_work_J = imp.impulses[static_cast<int>(rows.size()) - 1] * b.dot(v0);
  std::vector<double> st(q);
  st.insert(st.end(), qd.begin(), qd.end());
  for (int k = 0; k < n; ++k) st[static_cast<std::size_t>(n + k)] += imp.dv[k];
  st[static_cast<std::size_t>(c)] = c > 0 ? q[static_cast<std::size_t>(c - 1)] : y_[static_cast<std::size_t>(lo - 1)];  // D = 0
  set_end(ctx, st);
  closed_[static_cast<std::size_t>(e.bay)] = 1;
  if (c == 0) block_top_ = lo + (L.starts.size() > 1 ? L.starts[1] : L.frames) - 1;  // the cluster joins the block
  return e;
}

void FreeStack::init_deployed() {
  const double yr = mast_.rail.axis_height_m();
  y_[0] = yr - mast_.bay(1).strut_length_m;
  for (int k = 1; k <= mast_.n_bays(); ++k) y_[static_cast<std::size_t>(k)] = y_[static_cast<std::size_t>(k - 1)] + 2.0 * mast_.bay(k).strut_length_m;
  std::fill(v_.begin(), v_.end(), 0.0);
  std::fill(closed_.begin(), closed_.end(), 0);
  block_top_ = 0;  // frame 0 is held wherever a phase does not move it (it lands on the floor in bay 1's stage)
  retract_ = true;
  x_ = xi_ = 0.0;
}

FreeContactEvent FreeStack::apply_unlock(const PhaseContext& ctx, double u, bool drive_holds_speed, bool from_rest) {
  const int m = ctx.bay;
  // Bay m was locked straight on frame m-1, which drove it.
  y_[static_cast<std::size_t>(m)] = y_[static_cast<std::size_t>(m - 1)] + 2.0 * mast_.bay(m).strut_length_m;
  v_[static_cast<std::size_t>(m)] = v_[static_cast<std::size_t>(m - 1)];
  x_ = xi_ = 0.0;
  const int lo = calc_lowest_frame(PhaseKind::on_rail, m);
  FreePhaseB phase(ctx, lo, y_[0], kBaumgarteRate_per_s, bays_);
  if (contacts_) phase.set_contacts(make_layout(PhaseKind::on_rail, m, lo));
  std::vector<double> q, qd;
  get_start(ctx, q, qd);
  const int n = static_cast<int>(q.size());
  Eigen::VectorXd diag, sub;
  phase.calc_mass(q.data(), qd.data(), diag, sub);
  // At x = 0: rail gradient a = (.., 1, cot beta), driven frame b = (.., 1, 0) (docs/model.md §3).
  std::vector<Eigen::VectorXd> rows(1, Eigen::VectorXd::Zero(n));
  rows[0][n - 2] = 1.0;
  rows[0][n - 1] = mast_.rail.cot_beta();
  const Eigen::Map<const Eigen::VectorXd> v0(qd.data(), n);
  Eigen::Vector3d d(-rows[0].dot(v0), 0.0, 0.0);
  if (drive_holds_speed) {
    rows.emplace_back(Eigen::VectorXd::Unit(n, n - 2));
    d[1] = from_rest ? u - v0[n - 2] : 0.0;
  }
  TridiagonalWork w;
  const ConstrainedImpact imp = calc_constrained_impact(diag, sub, rows, d, w);
  FreeContactEvent e;
  e.handled = true;
  e.bay = m;
  e.ok = imp.ok;
  if (!imp.ok) return e;
  e.impulse_Ns = imp.impulses[0];
  e.rail_impulse_Ns = imp.impulses[0];
  if (drive_holds_speed && from_rest) {
    e.drive_work_J = imp.energy_loss_J;  // (1/2) dv' M dv: the energy the ramp gives (no loss)
    e.impulse_Ns = imp.impulses[1];
  } else {
    e.energy_loss_J = imp.energy_loss_J;
    if (drive_holds_speed) e.drive_work_J = imp.impulses[1] * u;
  }
  std::vector<double> st(q);
  st.insert(st.end(), qd.begin(), qd.end());
  for (int k = 0; k < n; ++k) st[static_cast<std::size_t>(n + k)] += imp.dv[k];
  set_end(ctx, st);
  return e;
}

FreeContactEvent FreeStack::apply_rail_exit(const StageSpec& s, bool drive_holds_speed) {
  const int m = s.bay;
  FreeContactEvent e;
  e.bay = m - 1;
  const double tol = 1e-6 * mast_.bay(std::max(m - 1, 1)).strut_length_m;  // f = 0 to the rail residual
  const bool on_block = contacts_ && m >= 2 && block_top_ >= m - 2 &&
                        std::abs(y_[static_cast<std::size_t>(m - 1)] - y_[static_cast<std::size_t>(m - 2)]) <= tol;
  if (m >= 2 && !on_block) return e;  // leaves the rail with its velocity: no impact
  e.handled = e.landing = true;
  const int lo = m - 1;
  if (m >= 2) block_top_ = m - 2;  // frames lo..m move in the impact, frame m - 1 alone in its cluster
  FrameSystem sys;
  Eigen::VectorXd v;
  calc_cluster_system(s, PhaseKind::open, lo, sys, v);
  const int n = static_cast<int>(v.size());
  std::vector<Eigen::VectorXd> rows(1, Eigen::VectorXd::Unit(n, 0));
  Eigen::Vector3d d(-v[0], 0.0, 0.0);
  if (drive_holds_speed) rows.emplace_back(Eigen::VectorXd::Unit(n, n - 1));
  TridiagonalWork w;
  const ConstrainedImpact imp = calc_constrained_impact(sys.diag, sys.sub, rows, d, w);
  e.ok = imp.ok;
  if (!imp.ok) return e;
  add_cluster_velocities(make_layout(PhaseKind::open, m, lo), lo, imp.dv);
  v_[static_cast<std::size_t>(m - 1)] = 0.0;
  y_[static_cast<std::size_t>(m - 1)] = m >= 2 ? y_[static_cast<std::size_t>(m - 2)] : 0.0;
  if (m >= 2) { closed_[static_cast<std::size_t>(m - 1)] = 1; block_top_ = m - 1; }
  e.energy_loss_J = imp.energy_loss_J;
  e.impulse_Ns = imp.impulses[0];
  if (drive_holds_speed) e.drive_work_J = imp.impulses[1] * v_[static_cast<std::size_t>(m)];
  return e;
}

void FreeStack::start_stage(int m) {
  if (!contacts_) return;
  closed_[static_cast<std::size_t>(m)] = 0;  // bay m deploys: no longer a contact
  block_top_ = std::min(block_top_, m - 1);
}

double FreeStack::calc_rail_function_m(int m) const {
  return model::calc_rail_function_m(mast_.rail, calc_hinge_offset_m(m),
                                     0.5 * (y_[static_cast<std::size_t>(m)] + y_[static_cast<std::size_t>(m - 1)]));
}

double FreeStack::calc_hinge_offset_m(int i) const {
  return model::calc_hinge_offset_m(mast_.bay(i), y_[static_cast<std::size_t>(i)] - y_[static_cast<std::size_t>(i - 1)]);
}

int FreeStack::find_straightest_bay(int top) const {
  int best = 1;
  for (int i = 2; i <= top; ++i)
    if (calc_hinge_offset_m(i) / mast_.bay(i).strut_length_m < calc_hinge_offset_m(best) / mast_.bay(best).strut_length_m) best = i;
  return best;
}

void FreeStack::get_frame_heights(int m, double* y) const {
  for (int k = 0; k <= m; ++k) y[k] = y_[static_cast<std::size_t>(k)];
  FreePhaseA::fill_locked_heights(mast_, m, y);
}

void FreeStack::apply_lock(int m) {
  y_[static_cast<std::size_t>(m)] = y_[static_cast<std::size_t>(m - 1)] + 2.0 * mast_.bay(m).strut_length_m;
  v_[static_cast<std::size_t>(m)] = v_[static_cast<std::size_t>(m - 1)];
  x_ = 0.0;
  xi_ = 0.0;
}

std::string FreeStack::describe_singular(int m, double t_s) const {
  const int i = find_straightest_bay(m - 1);
  return fmt::format("singular configuration: bay {} (not deploying) came within {:.3g} l_s of straight (hinge offset {:.6g} m) "
                     "at t = {:.9g} s in the stage of bay {}",
                     i, FreePhaseA::kStraightFraction, calc_hinge_offset_m(i), t_s, m);
}

std::string FreeStack::describe_rail_miss(int m, bool past_miss_height, double closest_m, double closest_t_s, double rail_top_t_s,
                                          double t_s) const {
  const std::string why = past_miss_height
      ? fmt::format("the driven frame passed the lock height plus one bay (y = {:.9g} m)", get_height_m(m))
      : fmt::format("bay {} straightened", m);
  const std::string top = std::isfinite(rail_top_t_s)
      ? fmt::format("above the rail top (y_r = {:.6g} m) from t = {:.9g} s", mast_.rail.axis_height_m(), rail_top_t_s)
      : std::string("never above the rail top");
  return fmt::format("rail miss: the hinge of bay {} never reached the rail; closest approach {:.6g} m at t = {:.9g} s; {}; "
                     "stopped at t = {:.9g} s when {}",
                     m, closest_m, closest_t_s, top, t_s, why);
}

}  // namespace truss::stages
