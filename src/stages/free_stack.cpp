#include "stages/free_stack.hpp"

#include <algorithm>
#include <cmath>

#include "model/bay.hpp"
#include "model/frames.hpp"
#include "model/impacts.hpp"
#include "model/rail.hpp"
#include "stages/free_phase.hpp"
#include "stages/free_phase_b.hpp"

namespace truss::stages {

using namespace truss::model;

FreeStack::FreeStack(const MastParams& mast)
    : mast_(mast), y_(static_cast<std::size_t>(mast.n_bays() + 1), 0.0), v_(y_.size(), 0.0) {}

std::unique_ptr<PhaseModel> FreeStack::make_phase(const PhaseContext& ctx, bool watch_rail_top, bool watch_approach_min) const {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay);
  const double held = y_[0];  // frame 0 is the only held frame below a free stack
  if (ctx.kind == PhaseKind::open) {
    auto a = std::make_unique<FreePhaseA>(ctx, lo, held);
    a->set_watch(watch_rail_top, watch_approach_min);
    return a;
  }
  return std::make_unique<FreePhaseB>(ctx, lo, held, kBaumgarteRate_per_s);
}

void FreeStack::get_start(const PhaseContext& ctx, std::vector<double>& q, std::vector<double>& qdot) const {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay), m = ctx.bay;
  q.assign(y_.begin() + lo, y_.begin() + m + 1);
  qdot.assign(v_.begin() + lo, v_.begin() + m + 1);
  if (ctx.kind == PhaseKind::on_rail) { q.back() = x_; qdot.back() = xi_; }
}

void FreeStack::set_end(const PhaseContext& ctx, const std::vector<double>& st) {
  const int lo = calc_lowest_frame(ctx.kind, ctx.bay), m = ctx.bay, n = m - lo + 1;
  for (int k = 0; k < n; ++k) {
    y_[static_cast<std::size_t>(lo + k)] = st[static_cast<std::size_t>(k)];
    v_[static_cast<std::size_t>(lo + k)] = st[static_cast<std::size_t>(n + k)];
  }
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

StackImpact FreeStack::apply_start_kick(const StageSpec& s, double u) {
  const int lo = calc_lowest_frame(PhaseKind::open, s.bay), first = std::max(lo - 1, 0);
  FrameSystem sys;
  calc_frame_system(mast_, make_active(s, lo), y_.data() + first, v_.data() + first, first, sys);
  TridiagonalWork w;
  StackImpact k = calc_stack_start_kick(sys.diag, sys.sub, u, w);
  if (k.ok)
    for (int i = 0; i < k.dv.size(); ++i) v_[static_cast<std::size_t>(lo + i)] += k.dv[i];
  return k;
}

FreeRailEntry FreeStack::apply_rail_entry(const StageSpec& s, bool drive_holds_speed) {
  const int m = s.bay, lo = calc_lowest_frame(PhaseKind::on_rail, m), first = std::max(lo - 1, 0);
  // Bay m in frame heights (regular off the lock), the moving set of phase B.
  FrameSystem sys;
  calc_frame_system(mast_, make_active(s, lo), y_.data() + first, v_.data() + first, first, sys);
  const double D = y_[static_cast<std::size_t>(m)] - y_[static_cast<std::size_t>(m - 1)];
  FreeRailEntry r;
  r.hinge_x_m = model::calc_hinge_offset_m(mast_.bay(m), D);
  const Eigen::Vector2d J = calc_rail_gradient(mast_.rail.cot_beta(), D, r.hinge_x_m);
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(v_.data() + lo, m - lo + 1);
  TridiagonalWork w;
  r.impact = calc_stack_rail_entry(sys.diag, sys.sub, v, J[0], J[1], drive_holds_speed, w);
  if (!r.impact.ok) return r;
  for (int i = 0; i < v.size(); ++i) v_[static_cast<std::size_t>(lo + i)] += r.impact.dv[i];
  // Hinge coordinate: D = 2 s, y_m' - y_{m-1}' = -(2x/s) x'.
  x_ = r.hinge_x_m;
  const double sh = 0.5 * D;
  xi_ = (v_[static_cast<std::size_t>(m - 1)] - v_[static_cast<std::size_t>(m)]) * sh / (2.0 * x_);
  return r;
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

}  // namespace truss::stages
