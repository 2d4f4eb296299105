// Optional time histories (docs/model.md §5): the phase points on the grid t_k = k * step, pushed in
// time order by the phase solvers, plus a last row at the end of the run.
// Memory is bounded in bytes: a row is calc_history_row_bytes(n_frames) (84 B, and 8 B a frame for
// the free stack's frame heights); when the rows reach run.max_history_bytes, every other row is
// dropped and the step doubles (the rows left are exactly the grid of the doubled step, t = 0, 2h,
// 4h, ...), so a long run keeps a coarser but complete history instead of exhausting memory. The
// vectors never grow past the cap either (their capacity is managed here). The step in force is
// TimeHistory::step_s (written as the `step_s` attribute of every history).
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "model/drive.hpp"
#include "stages/phase.hpp"
#include "stages/result.hpp"

namespace truss::stages {

// Bytes of one history row: t, 9 float64 columns and the bay (int32), plus n_frames frame heights.
inline constexpr long calc_history_row_bytes(int n_frames) { return 10 * 8 + 4 + 8L * n_frames; }

class HistoryRecorder {
 public:
  HistoryRecorder(TimeHistory* out, double step_s, const model::DriveParams& drive, long max_bytes)
      : out_(step_s > 0.0 ? out : nullptr), step_(step_s), drive_(drive), max_bytes_(max_bytes),
        max_rows_(std::max(2L, max_bytes / calc_history_row_bytes(0))) {
    if (out_) out_->step_s = step_s;
  }
  bool enabled() const { return out_ != nullptr; }
  // Free stack: also record the heights of frames 0..n_frames-1 per row. The caller writes them
  // into frame_buffer() before each sample (eval) and before finish(); NaN where it did not.
  void enable_frames(int n_frames) {
    if (!out_) return;
    out_->n_frames = n_frames;
    frames_.assign(static_cast<std::size_t>(n_frames), __builtin_nan(""));
    // SceneOptions::validate() refuses a cap below two rows, so this keeps to it.
    max_rows_ = std::max(2L, max_bytes_ / calc_history_row_bytes(n_frames));
  }
  bool records_frames() const { return out_ && out_->n_frames > 0; }
  double* frame_buffer() { return frames_.data(); }
  // Samples the grid times in [t0, t1); eval(t) gives the phase point at t. Returns false (and
  // stops sampling) once the wall-clock deadline has passed.
  template <class Eval>
  bool sample(Eval&& eval, double t0, double t1, int bay, std::chrono::steady_clock::time_point deadline) {
    if (!out_) return true;
    for (long k = 0;; ++k) {
      const double t = static_cast<double>(next_) * step_;
      if (t < t0 - 1e-12 * std::max(1.0, t0)) { ++next_; continue; }
      if (t >= t1) break;
      if ((k & 1023) == 1023 && std::chrono::steady_clock::now() > deadline) return false;
      push(t, eval(std::clamp(t, t0, t1)), bay);
      ++next_;
      if (static_cast<long>(out_->size()) >= max_rows_) decimate();
    }
    return true;
  }
  // The last row of a history is the end of the run (on the grid or not).
  void finish(double t, const PhasePoint& last, int bay) {
    if (out_ && (out_->t_s.empty() || out_->t_s.back() < t)) push(t, last, bay);
  }

 private:
  // Every column reserves the rows of the cap with the first row, and never moves after: a column
  // that grew by doubling would hold its old and its new block at once (1.5 times the cap at the
  // last doubling). The pages no row reaches are never touched, so they are not resident: the
  // memory in use is the rows held, at most the cap.
  void reserve_rows() {
    const auto rows = static_cast<std::size_t>(max_rows_);
    if (out_->t_s.capacity() >= rows) return;
    for (auto* v : {&out_->t_s, &out_->y_driven_m, &out_->y_lower_m, &out_->hinge_x_m, &out_->hinge_y_m,
                    &out_->drive_force_N, &out_->drive_torque_Nm, &out_->pin_force_N, &out_->diagonal_tension_N,
                    &out_->driven_speed_m_per_s})
      v->reserve(rows);
    out_->bay.reserve(rows);
    out_->frame_height_m.reserve(rows * static_cast<std::size_t>(out_->n_frames));
  }
  void push(double t, const PhasePoint& p, int bay) {
    reserve_rows();
    out_->t_s.push_back(t);
    out_->bay.push_back(bay);
    out_->y_driven_m.push_back(p.y_driven_m);
    out_->y_lower_m.push_back(p.y_lower_m);
    out_->hinge_x_m.push_back(p.hinge_x_m);
    out_->hinge_y_m.push_back(p.hinge_y_m);
    out_->drive_force_N.push_back(p.drive_force_N);
    out_->drive_torque_Nm.push_back(drive_.calc_torque_Nm(p.drive_force_N));
    out_->pin_force_N.push_back(p.pin_force_N);
    out_->diagonal_tension_N.push_back(p.diagonal_tension_N);
    out_->driven_speed_m_per_s.push_back(p.u_m_per_s);
    if (out_->n_frames > 0) {
      out_->frame_height_m.insert(out_->frame_height_m.end(), frames_.begin(), frames_.end());
      std::fill(frames_.begin(), frames_.end(), __builtin_nan(""));
    }
  }
  // Keeps the rows on even grid points (t = k step, k even: k is exact as t / step rounded).
  template <class V>
  void keep_even(V& v, const std::vector<char>& keep) const {
    std::size_t j = 0;
    for (std::size_t i = 0; i < v.size(); ++i)
      if (keep[i]) v[j++] = v[i];
    v.resize(j);
  }
  void decimate() {
    std::vector<char> keep(out_->size());
    for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = std::llround(out_->t_s[i] / step_) % 2 == 0;
    keep_even(out_->bay, keep); keep_even(out_->y_driven_m, keep); keep_even(out_->y_lower_m, keep);
    keep_even(out_->hinge_x_m, keep); keep_even(out_->hinge_y_m, keep); keep_even(out_->drive_force_N, keep);
    keep_even(out_->drive_torque_Nm, keep); keep_even(out_->pin_force_N, keep); keep_even(out_->diagonal_tension_N, keep);
    keep_even(out_->driven_speed_m_per_s, keep);
    if (out_->n_frames > 0) {  // rows of n_frames values
      const std::size_t w = static_cast<std::size_t>(out_->n_frames);
      std::size_t j = 0;
      for (std::size_t i = 0; i < keep.size(); ++i)
        if (keep[i]) std::copy_n(out_->frame_height_m.begin() + static_cast<std::ptrdiff_t>(i * w), w,
                                 out_->frame_height_m.begin() + static_cast<std::ptrdiff_t>(j++ * w));
      out_->frame_height_m.resize(j * w);
    }
    keep_even(out_->t_s, keep);
    step_ *= 2.0;
    next_ = (next_ + 1) / 2;  // the next grid point of the doubled step at or after the old one
    out_->step_s = step_;
  }
  TimeHistory* out_;
  double step_;
  long next_ = 0;
  const model::DriveParams& drive_;
  long max_bytes_;
  long max_rows_;
  std::vector<double> frames_;
};

}  // namespace truss::stages
