// From a run's uniforms to its dispersed scene and mast. Each dispersion owns a fixed block of
// sampling dimensions: 1 (per run), n_max (per bay) or n_max + 1 (per frame), n_max the largest
// bay count the campaign can draw, so that a run's draws depend only on (seed, run index) and
// never on the bay count drawn for it: bay k gets the same draw in a 10-bay and a 60-bay run.
#pragma once
#include <algorithm>
#include <vector>

#include "campaign/campaign.hpp"
#include "sampling/sampling.hpp"
#include "model/params.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

using sampling::Distribution;

struct DimensionLayout {
  std::vector<int> offset;  // first dimension of each dispersion
  std::vector<int> count;   // its number of dimensions
  int total = 0;            // dimensions per run
  int n_bays_max = 0;       // largest bay count a run can have
  std::vector<Distribution> distributions;  // one per dispersion, built once
  std::vector<const sim::SceneKey*> keys;   // each dispersion's scene key, looked up once
  // Each bay's J_c follows its (dispersed) strut mass and length: J_c neither set nor dispersed.
  bool strut_inertia_follows = true;
  // A sweep (campaign/design_axis.hpp): the design coordinate is the last dimension, u = (k + 0.5) / n for
  // design value k of n (-1: no sweep); a nominal sweep's scene key, or a spread sweep's dispersion
  // and its distribution at each design value.
  int design = -1;
  std::size_t n_design_values = 0;
  const sim::SceneKey* sweep_key = nullptr;
  int sweep_dispersion = -1;
  std::vector<Distribution> sweep_distributions;
  // The dimensions the dispersions draw (a method's points): all but the design coordinate.
  int dispersion_dims() const { return design >= 0 ? design : total; }
  // The sweep's value index of a run's design coordinate.
  std::size_t find_sweep_index(double u, std::size_t n_design_values) const {
    return std::min(n_design_values - 1, static_cast<std::size_t>(u * static_cast<double>(n_design_values)));
  }
};

// Throws std::invalid_argument naming the dispersion if a distribution is unusable (the campaign
// parser has already rejected such files with file:line messages).
DimensionLayout calc_layout(const CampaignOptions& c);

Distribution make_distribution(const DispersionOptions& d);

// Plausibility of dispersion i of a campaign whose base scene is resolved: the draws it makes in
// practice, the distribution's 3-sigma quantiles (0.135 % and 99.865 %; every value of a discrete
// table), applied to every bay (frame) with the other dispersions at their medians, must give a
// scene the model accepts (the checks simulate() makes). Empty, or why not: the quantile, the
// value it gives and the model's refusal, with a hint for a relative draw (a fraction, not a
// percentage). A campaign that fails this would record most of its runs as invalid input.
std::string check_dispersion_draws(const CampaignOptions& c, std::size_t i);

// Nominal value of a dispersible scene key in the base scene (per-bay and per-frame keys: the
// scene's single value). NaN for a key that is not dispersible.
double find_nominal(const sim::SceneOptions& s, const std::string& key);
// Units of a scene key, from its name's suffix ("_kg" -> "kg", "_N_per_m" -> "N/m"); "1" if none.
std::string find_key_units(const std::string& key);

struct RunInputs {
  sim::SceneOptions scene;               // base scene with the per-run draws applied
  model::MastParams mast;                // per-bay and per-frame values applied
  // Sampled values per dispersion: 1 entry (per run) or n_max / n_max + 1 entries (per bay /
  // frame), NaN for bays or frames beyond the run's bay count. In the key's own units. A sweep's
  // run has one more entry: its design value.
  std::vector<std::vector<double>> values;
};

// u: layout.total uniforms of one run.
RunInputs calc_run_inputs(const CampaignOptions& c, const DimensionLayout& layout, const double* u);

}  // namespace truss::campaign
