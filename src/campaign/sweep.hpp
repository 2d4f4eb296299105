// A design sweep ([sweep] of a campaign file): the campaign's failure probability at each of a
// list of values of one design variable, and the allowable (methods/sweep_method.hpp runs it).
//
//   [sweep]
//   key = "drive.stall_torque_Nm"     # a real scene key: its nominal value takes each value
//   spread = "mast.diagonal_free_length_m"  # or, instead of key: the spread of the [[dispersion]]
//                                     # of that key (normal and truncated normal: std; lognormal:
//                                     # sigma; uniform: the half-width about the centre of lower, upper)
//   values = [0.012, 0.015, 0.018]    # strictly ascending, at least 2; or
//   from = 0.012, to = 0.020, count = 5   # evenly spaced, from < to
//   target_probability = 1e-6         # in (0, 1)
//   confidence = 0.95                 # of the one-sided upper bound on p (default 0.95)
//   refine = 3                        # after the values: this many more, evenly inside the bracket
//                                     # of the allowable (default 0: none)
//
// The design values a sweep can run, indexed k: first the listed values x_0 < ... < x_{n-1}
// (k < n), then, with refine = m, m candidates inside each bracket (x_i, x_{i+1}), evenly spaced:
// k = n + i m + j is x_i + (j + 1) (x_{i+1} - x_i) / (m + 1), j < m. The listed values always run;
// the refinement runs the m candidates of one bracket, the one that holds the allowable found from
// the listed values (methods/sweep_method.hpp). Every candidate is fixed by the file alone, so any
// rank knows any value and its runs are keyed by k like the listed ones.
//
// Value k of the sweep is the standalone campaign calc_campaign_at(c, k): the same file without
// [sweep], the design value written into the base scene (key) or the dispersion (spread), and
// ensemble.master_seed = calc_sweep_seed(master_seed, k). Its runs are that campaign's runs, point
// for point.
//
// A run of a sweep carries its value as one more sampling dimension, the last of the layout
// (DimensionLayout::design): u = (k + 0.5) / n_design_values(), so a run's uniforms still say
// everything about it (calc_run_inputs applies the value), and /runs/sweep_value records it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace truss::campaign {

struct CampaignOptions;

enum class SweepVariable { nominal, spread };

struct SweepOptions {
  bool active = false;                       // a [sweep] table was given
  SweepVariable variable = SweepVariable::nominal;
  std::string key;                           // the scene key (nominal) or the dispersed key (spread)
  std::vector<double> values;                // strictly ascending, in the key's unit
  int refine = 0;                            // candidates per bracket; one bracket's run (0: no refinement)
  double target_probability = 0.0;          // the allowable keeps the upper bound on p at or below this
  double confidence = 0.95;                  // of that one-sided upper bound
  int line = 0;                              // of the [sweep] table, for messages
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
inline std::size_t calc_max_design_values(const SweepOptions& s) {
  return s.n_values() + static_cast<std::size_t>(s.refine);
}

// The master seed of value k's runs: SplitMix64 of (master seed, k), 63 bits (a campaign file's
// integer).
std::uint64_t calc_sweep_seed(std::uint64_t master_seed, std::size_t k);

// The standalone campaign of value k (see above): no [sweep], the value applied, its seed.
CampaignOptions calc_campaign_at(const CampaignOptions& c, std::size_t k);

// The sweep's own rules (part of CampaignOptions::validate): "" or "sweep.<field>: reason". The
// design variable exists and can take each value (the scene and every dispersion's plausibility
// checked at each value), the inner method estimates a probability of the [failure] event.
std::string validate_sweep(const CampaignOptions& c);

// [sweep] as resolved TOML (values listed), or "" without a sweep.
std::string sweep_toml(const SweepOptions& s);

}  // namespace truss::campaign
