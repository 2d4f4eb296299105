// Optional time histories (MODEL.md 5): the phase points on the grid t_k = k * output_step_s,
// pushed in time order by the phase solvers, plus a last row at the end of the run.
#pragma once
#include <algorithm>

#include "model/drive.hpp"
#include "stages/phase.hpp"
#include "stages/result.hpp"

namespace truss::stages {

class HistoryRecorder {
 public:
  HistoryRecorder(TimeHistory* out, double step_s, const model::DriveParams& drive)
      : out_(step_s > 0.0 ? out : nullptr), step_(step_s), drive_(drive) {}
  bool enabled() const { return out_ != nullptr; }
  // Samples the grid times in [t0, t1); eval(t) gives the phase point at t.
  template <class Eval>
  void sample(Eval&& eval, double t0, double t1, int bay) {
    if (!out_) return;
    while (true) {
      const double t = static_cast<double>(next_) * step_;
      if (t < t0 - 1e-12 * std::max(1.0, t0)) { ++next_; continue; }
      if (t >= t1) break;
      push(t, eval(std::clamp(t, t0, t1)), bay);
      ++next_;
    }
  }
  // The last row of a history is the end of the run (on the grid or not).
  void finish(double t, const PhasePoint& last, int bay) {
    if (out_ && (out_->t_s.empty() || out_->t_s.back() < t)) push(t, last, bay);
  }

 private:
  void push(double t, const PhasePoint& p, int bay) {
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
  }
  TimeHistory* out_;
  double step_;
  long next_ = 0;
  const model::DriveParams& drive_;
};

}  // namespace truss::stages
