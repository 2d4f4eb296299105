#include "stages/free_stack.hpp"

#include <algorithm>
#include <cmath>

#include "model/bay.hpp"
#include "model/contacts.hpp"
#include "model/frames.hpp"
#include "model/impacts.hpp"
#include "model/rail.hpp"
#include "stages/free_phase.hpp"
#include "stages/free_phase_b.hpp"

namespace truss::stages {

using namespace truss::model;

FreeStack::FreeStack(const MastParams& mast, bool contacts)
    : mast_(mast), contacts_(contacts), y_(static_cast<std::size_t>(mast.n_bays() + 1), 0.0), v_(y_.size(), 0.0),
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
  for (int i = lo; i <= top; ++i)
    if (i == lo || i == m || !closed_[static_cast<std::size_t>(i)]) L.starts.push_back(i - lo);
  return L;
}

std::unique_ptr<PhaseModel> FreeStack::make_phase(const PhaseContext& ctx, bool watch_rail_top, bool watch_approach_min) const {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay);
  last_lo_ = lo;
  const double held = y_[0];  // frame 0 and the resting block are the only held frames (height 0)
  if (ctx.kind == PhaseKind::open) {
    auto a = std::make_unique<FreePhaseA>(ctx, lo, held);
    a->set_watch(watch_rail_top, watch_approach_min);
    if (contacts_) a->set_contacts(make_layout(ctx.kind, ctx.bay, lo));
    return a;
  }
  auto b = std::make_unique<FreePhaseB>(ctx, lo, held, kBaumgarteRate_per_s);
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
  StackImpact k = calc_stack_start_kick(sys.diag, sys.sub, u, w);
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
    FreePhaseA a(ctx, lo, y_[0]);
    a.set_contacts(make_layout(ctx.kind, ctx.bay, lo));
    return a.calc_contact_watch(q.data(), qd.data());
  }
  FreePhaseB b(ctx, lo, y_[0], kBaumgarteRate_per_s);
  b.set_contacts(make_layout(ctx.kind, ctx.bay, lo));
  return b.calc_contact_watch(q.data(), qd.data());
}

void FreeStack::open_contact(int j) {
  closed_[static_cast<std::size_t>(j)] = 0;
  if (j <= block_top_) block_top_ = j - 1;
}

int FreeStack::prepare_segment(const PhaseContext& ctx) {
  if (!contacts_) return 0;
  int opened = 0;
  // Active set: open the most pulling contact and look again (each pass opens one; at most n).
  for (int it = 0; it <= mast_.n_bays(); ++it) {
    const ContactWatch w = watch_at(ctx);
    if (!(w.lift_off_g > 0.0)) break;
    open_contact(w.lift_off_bay);
    ++opened;
  }
  return opened;
}

FreeContactEvent FreeStack::apply_contact_event(const PhaseContext& ctx, int stop_event, bool drive_holds_speed) {
  FreeContactEvent e;
  const bool open = ctx.kind == PhaseKind::open;
  const int landing = open ? FreePhaseA::contact_landing : 1, lift = open ? FreePhaseA::contact_lift_off : 2;
  if (!contacts_ || (stop_event != landing && stop_event != lift)) return e;
  e.handled = true;
  const ContactWatch w = watch_at(ctx);
  if (stop_event == lift) {
    e.bay = w.lift_off_bay;
    open_contact(e.bay);
    return e;
  }
  e.landing = true;
  e.bay = w.landing_bay;
  const int m = ctx.bay, lo = calc_lowest_frame(ctx.kind, m);
  const ContactLayout L = make_layout(ctx.kind, m, lo);
  std::vector<double> q, qd;
  get_start(ctx, q, qd);
  const int n = static_cast<int>(q.size());
  int c = 0;
  while (lo + L.starts[static_cast<std::size_t>(c)] != e.bay) ++c;
  Eigen::VectorXd diag, sub;
  if (open) {
    FreePhaseA a(ctx, lo, y_[0]);
    a.set_contacts(L);
    a.calc_mass(q.data(), qd.data(), diag, sub);
  } else {
    FreePhaseB b(ctx, lo, y_[0], kBaumgarteRate_per_s);
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

void FreeStack::apply_lock(int m) {
  y_[static_cast<std::size_t>(m)] = y_[static_cast<std::size_t>(m - 1)] + 2.0 * mast_.bay(m).strut_length_m;
  v_[static_cast<std::size_t>(m)] = v_[static_cast<std::size_t>(m - 1)];
  x_ = 0.0;
  xi_ = 0.0;
}

}  // namespace truss::stages
