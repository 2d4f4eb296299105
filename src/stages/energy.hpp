// Energy ledger of a run (docs/model.md §5): drive work (smooth part and impulses), the energy lost in
// every impact, the kinetic and potential energies at start and end, and the residual
//   W - (T_end - T_start) - (U_end - U_start) - E_lost,
// which closes to the integration error. The potential of the bays that do not move in a stage
// (stowed at D = 0 below, locked at D = 2 l_s above) comes from prefix / suffix sums: O(1) per
// look-up after an O(n) set-up.
#pragma once
#include <string>
#include <vector>

#include "model/params.hpp"
#include "stages/result.hpp"

namespace truss::stages {

// Accuracy health check (docs/model-notes.md, "Accuracy check"). The energy scale E of a run is
// the sum of the magnitudes of the ledger's terms. A run integrated to rtol over its 2 n phases
// keeps its residual within a bound that grows with the phases (each is a restart with its own
// local errors and a located event): measured on Table 1 (60 phases, every mode and direction,
// rtol 1e-4..1e-12) at most 240 rtol E, i.e. 4 rtol E per phase. Where atol dominates (rtol near
// 1e-13) positions are held to atol, atol / l_s relative to a bay; and the drive-work state W (J)
// gains up to atol per accepted step. The bound, with a safety factor of 5 on the measured 4:
//   allowed = min(1e-2 E,  20 max(60, 2 n) max(rtol, atol / l_s) E + steps atol)
// (a share of the error does not shrink with fewer phases: one-bay runs reach 50 rtol E).
// A run beyond it (or beyond 1 % of E whatever the tolerance) does not keep its balance to what
// its tolerance allows: status `inaccurate`.
double calc_energy_scale_J(const RunResult& r);
double calc_allowed_energy_residual_J(const RunResult& r, double rtol, double atol, double length_m);
// The relative error a run of n bays at (rtol, atol) keeps, the bound's factor of E above:
// min(1e-2, 20 max(60, 2 n) max(rtol, atol / l_s)). Also the tolerance within which two peaks are
// one (peaks.hpp).
double calc_allowed_relative_error(int n_bays, double rtol, double atol, double length_m);
// With stack contacts (contacts = true) the frames may overlap only by what locating a contact event
// leaves, kContactOverlapFraction l_s (measured: 1e-9 l_s at every tolerance from 1e-3 to 1e-12, the
// root finder's position tolerance); a deeper overlap means a crossing was missed inside a step.
inline constexpr double kContactOverlapFraction = 2e-9;
// Empty if the run keeps the promise of `ok` (its reported numbers finite, its residual within
// the bound above, no overlap beyond the contacts' bound); otherwise the reason, for `inaccurate`.
std::string calc_accuracy_failure(const RunResult& r, double rtol, double atol, double length_m, bool contacts);

class EnergyLedger {
 public:
  explicit EnergyLedger(const model::MastParams& mast);
  // Whole-mast potential in the stage of `bay`: locked bays above it, the moving bays'
  // `moving_J`, and the stowed bays below `first_moving_frame` (J).
  double calc_total_potential_J(int bay, int first_moving_frame, double moving_J) const {
    return U_locked_suffix_[static_cast<std::size_t>(bay + 1)] + moving_J +
           U_stowed_prefix_[static_cast<std::size_t>(first_moving_frame - 1)];
  }
  double get_stowed_potential_J() const { return U_stowed_prefix_.back(); }
  double get_deployed_potential_J() const { return U_locked_suffix_[1]; }

  void add_smooth_work(double J) { smooth_J_ += J; }
  void add_impulse_work(double J) { impulses_J_ += J; }
  void add_loss(double J) { lost_J_ += J; }
  void set_start(double kinetic_J, double potential_J) { T0_ = kinetic_J; U0_ = potential_J; }
  void set_end(double kinetic_J, double potential_J) { T1_ = kinetic_J; U1_ = potential_J; }
  // Writes every energy field of the result, the residual last.
  void fill(RunResult& r) const;

 private:
  std::vector<double> U_stowed_prefix_, U_locked_suffix_;
  double smooth_J_ = 0, impulses_J_ = 0, lost_J_ = 0;
  double T0_ = 0, U0_ = 0, T1_ = 0, U1_ = 0;
};

}  // namespace truss::stages
