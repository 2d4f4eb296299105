// The rows of a campaign file's own tables (campaign_tables.hpp).
#include "campaign/campaign_tables.hpp"

#include "sampling/sampling.hpp"

namespace truss::campaign {

namespace {

using C = CampaignOptions;
using D = DispersionOptions;

bool runs_not_chosen(const C& c) { return !c.ensemble.method || c.ensemble.method.options().chosen_runs().empty(); }
bool is_normal(const D& d) {
  return d.distribution == DistributionKind::normal || d.distribution == DistributionKind::truncated_normal;
}
bool is_bounded(const D& d) {
  return d.distribution == DistributionKind::truncated_normal || d.distribution == DistributionKind::uniform;
}
bool is_lognormal(const D& d) { return d.distribution == DistributionKind::lognormal; }
bool is_discrete(const D& d) { return d.distribution == DistributionKind::discrete; }
bool has_weights(const D& d) { return is_discrete(d) && !d.weights.empty(); }

}  // namespace

const OptionTable<C>& campaign_table() {
  static const OptionTable<C> t{"campaign", "what the campaign is: its name and a line of description", {
      TRUSS_OPTION_TEXT(C, "name", name, "the campaign's name (the report's title)"),
      TRUSS_OPTION_TEXT(C, "description", description, "one line on what it studies"),
  }};
  return t;
}

const OptionTable<C>& ensemble_table() {
  static const OptionTable<C> t{"ensemble", "the runs: how many, their seed, their design and the method", {
      written_if(TRUSS_OPTION_INT(C, "n_runs", ensemble.n_runs, "1", at_least(1), "number of deployments"),
                 &runs_not_chosen),
      TRUSS_OPTION_INT(C, "master_seed", ensemble.master_seed, "1", at_least(0),
                       "with the run index, the only source of randomness"),
      TRUSS_OPTION_CHOICE(C, "sampling", ensemble.sampling, "the design of the runs' points",
                          choice_names(sampling::kSamplingNames)),
      TRUSS_OPTION_REAL(C, "max_run_wall_time_s", ensemble.max_run_wall_time_s, "s", kAnyNumber,
                        "a run longer than this is stopped and recorded (the range of run.max_wall_time_s)"),
      OptionRow<C>{{"method", OptionKind::method, "", {}, "how the runs are chosen: a row of the method table"},
                   nullptr, nullptr, nullptr, nullptr,
                   [](C&, const std::string&) {},  // the row reads its tables (method_input.hpp)
                   [](const C& c) { return c.ensemble.method.written_name(); }},
  }};
  return t;
}

const OptionTable<C>& output_table() {
  static const OptionTable<C> t{"output", "what is stored besides every run's record", {
      TRUSS_OPTION_INTS(C, "history_runs", output.history_runs, "1", at_least(0),
                        "runs whose time histories are stored (run again at the end)"),
      TRUSS_OPTION_REAL(C, "history_step_s", output.history_step_s, "s", above(0.0), "their sample step"),
  }};
  return t;
}

const OptionTable<C>& scene_table() {
  static const OptionTable<C> t{"scene", "the base scene: a file, then inline tables, then overrides", {
      written_if(TRUSS_OPTION_TEXT(C, "file", scene_file,
                                   "a scene file, relative to the campaign file (none: the Table-1 defaults)"),
                 &never_written<C>),
      OptionRow<C>{{"overrides", OptionKind::settings, "", {},
                    "scene keys set after the file and the inline tables: { \"drive.mode\" = \"motor\" }"},
                   nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr,
                   [](C& c, const std::vector<io::SceneSetting>& v) {
                     c.scene_settings.insert(c.scene_settings.end(), v.begin(), v.end());
                   }},
  }};
  return t;
}

const OptionTable<D>& dispersion_table() {
  static const OptionTable<D> t{"[[dispersion]]", "one dispersed scene key: which, how it applies, its distribution", {
      required(TRUSS_OPTION_TEXT(D, "key", key, "the scene key to disperse, e.g. \"mast.strut_mass_kg\"")),
      TRUSS_OPTION_CHOICE(D, "per", per, "one draw per run, per bay or per frame", "run", "bay", "frame"),
      TRUSS_OPTION_CHOICE(D, "apply", apply, "absolute: the draw; relative: nominal (1 + draw); offset: nominal + draw",
                          "absolute", "relative", "offset"),
      required(TRUSS_OPTION_CHOICE(D, "distribution", distribution, "the draws' distribution",
                                   choice_names(sampling::kDistributionNames))),
      written_if(TRUSS_OPTION_REAL(D, "mean", mean, "the draw's", kAnyNumber, "normal, truncated normal"), &is_normal),
      written_if(TRUSS_OPTION_REAL(D, "std", std, "the draw's", kAnyNumber, "normal, truncated normal"), &is_normal),
      written_if(TRUSS_OPTION_REAL(D, "lower", lower, "the draw's", kAnyNumber, "uniform; truncation"), &is_bounded),
      written_if(TRUSS_OPTION_REAL(D, "upper", upper, "the draw's", kAnyNumber, "uniform; truncation"), &is_bounded),
      written_if(TRUSS_OPTION_REAL(D, "mu", mu, "1", kAnyNumber, "lognormal: mean of ln X"), &is_lognormal),
      written_if(TRUSS_OPTION_REAL(D, "sigma", sigma, "1", kAnyNumber, "lognormal: std of ln X"), &is_lognormal),
      written_if(TRUSS_OPTION_REALS(D, "values", values, "the draw's", "discrete: the values"), &is_discrete),
      written_if(TRUSS_OPTION_REALS(D, "weights", weights, "1", "discrete: their weights (default: equal)"),
                 &has_weights),
  }};
  return t;
}

}  // namespace truss::campaign
