#include "stages/energy.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "model/bay.hpp"

namespace truss::stages {

EnergyLedger::EnergyLedger(const model::MastParams& mast) {
  const int n = mast.n_bays();
  U_stowed_prefix_.assign(static_cast<std::size_t>(n + 1), 0.0);
  U_locked_suffix_.assign(static_cast<std::size_t>(n + 2), 0.0);
  for (int i = 1; i <= n; ++i) {
    const double b2 = model::calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    U_stowed_prefix_[i] = U_stowed_prefix_[i - 1] + model::calc_bay_potential_J(mast.bay(i), b2, 0.0);
  }
  for (int i = n; i >= 1; --i) {
    const double b2 = model::calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    U_locked_suffix_[i] = U_locked_suffix_[i + 1] +
                          model::calc_bay_potential_J(mast.bay(i), b2, 2.0 * mast.bay(i).strut_length_m);
  }
}

double calc_energy_scale_J(const RunResult& r) {
  return std::abs(r.drive_work_smooth_J) + std::abs(r.drive_work_impulses_J) + std::abs(r.energy_lost_J) +
         std::abs(r.kinetic_energy_start_J) + std::abs(r.kinetic_energy_end_J) + std::abs(r.potential_energy_start_J) +
         std::abs(r.potential_energy_end_J);
}

double calc_allowed_relative_error(int n_bays, double rtol, double atol, double length_m) {
  // A run's error has a share that does not shrink with fewer phases (start, impacts, the events'
  // location): short masts get the bound of Table 1's 60 phases (measured up to 50 rtol E at n = 1).
  const double phases = std::max(60.0, 2.0 * n_bays);
  return std::min(1e-2, 20.0 * phases * std::max(rtol, atol / length_m));
}

double calc_allowed_energy_residual_J(const RunResult& r, double rtol, double atol, double length_m) {
  const double E = calc_energy_scale_J(r);
  return std::min(1e-2 * E, calc_allowed_relative_error(r.n_bays, rtol, atol, length_m) * E + static_cast<double>(r.steps) * atol);
}

std::string calc_accuracy_failure(const RunResult& r, double rtol, double atol, double length_m, bool contacts) {
  const std::pair<const char*, double> reported[] = {
      {"deploy_time_s", r.deploy_time_s}, {"peak_drive_force_N", r.peak_drive_force_N},
      {"min_drive_force_N", r.min_drive_force_N}, {"peak_pin_force_N", r.peak_pin_force_N},
      {"peak_diagonal_tension_N", r.peak_diagonal_tension_N}, {"drive_work_J", r.drive_work_J},
      {"energy_lost_J", r.energy_lost_J}, {"energy_residual_J", r.energy_residual_J}};
  for (const auto& [name, v] : reported)
    if (!std::isfinite(v)) return fmt::format("{} is not finite ({}) at the end of the run", name, v);
  if (contacts && r.min_bay_opening_m < -kContactOverlapFraction * length_m)
    return fmt::format("bay {} overlapped by {:.3g} m at t = {:.9g} s with stack contacts on, deeper than locating a "
                       "contact leaves ({:g} l_s = {:.3g} m): a contact was crossed inside a step; tighten run.rtol",
                       r.min_bay_opening_bay, -r.min_bay_opening_m, r.min_bay_opening_time_s, kContactOverlapFraction,
                       kContactOverlapFraction * length_m);
  const double allowed = calc_allowed_energy_residual_J(r, rtol, atol, length_m), E = calc_energy_scale_J(r);
  if (std::abs(r.energy_residual_J) <= allowed) return {};
  return fmt::format("energy residual {:.3g} J exceeds the {:.3g} J that rtol = {:g}, atol = {:g} allow ({:.3g} of the "
                     "energy scale {:.6g} J): the numbers of this run are not to be trusted; tighten run.rtol / run.atol",
                     r.energy_residual_J, allowed, rtol, atol, allowed / E, E);
}

void EnergyLedger::fill(RunResult& r) const {
  r.drive_work_smooth_J = smooth_J_;
  r.drive_work_impulses_J = impulses_J_;
  r.energy_lost_J = lost_J_;
  r.kinetic_energy_start_J = T0_;
  r.kinetic_energy_end_J = T1_;
  r.potential_energy_start_J = U0_;
  r.potential_energy_end_J = U1_;
  r.drive_work_J = r.drive_work_smooth_J + r.drive_work_impulses_J;
  r.energy_residual_J = r.drive_work_J - (r.kinetic_energy_end_J - r.kinetic_energy_start_J) -
                        (r.potential_energy_end_J - r.potential_energy_start_J) - r.energy_lost_J;
}

}  // namespace truss::stages
