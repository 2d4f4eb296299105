// The design variable of a design sweep as the campaign sees it. A sweep ([sweep], a composite
// method: methods/sweep_method.hpp) runs the campaign's method at each of a list of values of one
// design variable: a scene key's nominal value, or the spread of a dispersion. Its options hold
// this axis (MethodOptions::design_axis()); the campaign reads it to evaluate a run: the value is
// the run's last uniform, its inputs take the value, its record carries it (/runs/sweep_value).
//
// The design values a sweep can run, indexed k: first the listed values x_0 < ... < x_{n-1}
// (k < n), then, with refine = m, m candidates inside each bracket (x_i, x_{i+1}), evenly spaced:
// k = n + i m + j is x_i + (j + 1) (x_{i+1} - x_i) / (m + 1), j < m. Every candidate is fixed by the
// file alone, so any rank knows any value and its runs are keyed by k like the listed ones.
//
// Value k is the standalone campaign calc_campaign_at(c, k): the same file without [sweep] (its
// method the one the sweep runs), the value written into the base scene (key) or the dispersion
// (spread), and the file's ensemble.master_seed: every value draws the same random numbers (common
// random numbers), so neighbouring values differ by the design change, not by noise. Each value's
// estimate keeps its own distribution (its bounds hold value by value); only their differences
// lose the noise (the allowable's fixed-sequence reading needs no independence between values).
// Its runs are that campaign's runs, point for point. A run carries its value as one more sampling dimension, the last
// of the layout (DimensionLayout::design): u = (k + 0.5) / n_design_values().
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace truss::campaign {

struct CampaignOptions;

enum class SweepVariable { nominal, spread };

struct DesignAxis {
  SweepVariable variable = SweepVariable::nominal;
  std::string key;             // the scene key (nominal) or the dispersed key (spread)
  std::vector<double> values;  // strictly ascending, in the variable's unit
  int refine = 0;              // candidates per bracket; one bracket's run (0: no refinement)
  std::size_t n_values() const { return values.size(); }  // the listed values
  // Listed values and refinement candidates: the indices k a run can carry.
  std::size_t n_design_values() const {
    return values.empty() ? 0 : values.size() + (values.size() - 1) * static_cast<std::size_t>(refine);
  }
  // Design value k (see above); k < n_design_values().
  double find_value(std::size_t k) const;
  // The index of candidate j (< refine) of the bracket (x_i, x_{i+1}).
  std::size_t find_candidate_index(std::size_t i, int j) const {
    return values.size() + i * static_cast<std::size_t>(refine) + static_cast<std::size_t>(j);
  }
};

// The campaign's design axis (its method's, MethodOptions::design_axis()), or null.
const DesignAxis* find_design_axis(const CampaignOptions& c);

// The index of the dispersion whose spread a spread sweep sets (-1: none, or a nominal sweep).
int find_sweep_dispersion(const CampaignOptions& c);
// The design variable's name as /sweep and the report show it: "drive.stall_torque_Nm", or
// "mast.diagonal_free_length_m std" (half_width, sigma).
std::string sweep_variable_name(const CampaignOptions& c);
std::string sweep_variable_units(const CampaignOptions& c);
// The nominal value of the design variable in the campaign as written (the scene's key, or the
// dispersion's spread): what the verdict compares the allowable with.
double calc_sweep_own_value(const CampaignOptions& c);

// The most design values a sweep runs: the listed ones and one bracket's candidates (what memory
// and disk are checked for).
inline std::size_t calc_max_design_values(const DesignAxis& a) {
  return a.n_values() + static_cast<std::size_t>(a.refine);
}


// Design value k of c's axis written into `at` (a copy of c): the base scene's key, or the spread
// of the swept dispersion.
void apply_design_value(const CampaignOptions& c, std::size_t k, CampaignOptions& at);

// The standalone campaign of value k (see above): the composite's inner method, no axis, the value
// applied, its seed.
CampaignOptions calc_campaign_at(const CampaignOptions& c, std::size_t k);

// The axis' rules (part of CampaignOptions::validate): "" or "sweep.<field>: reason". The variable
// exists and can take each value: in the key's range, a scene the model takes and plausible
// dispersions at every value the sweep can run (the refinement's candidates too).
std::string validate_design_axis(const CampaignOptions& c);

}  // namespace truss::campaign
