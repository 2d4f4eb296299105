// Campaign files (TOML): a base scene, an ensemble (run count, master seed, sampling method) and
// dispersions of scene keys, parsed once into plain option structs and validated before any MPI
// work. Unknown tables and keys are errors (file:line), as in scene files. Each table's keys are
// rows of its option table (campaign_tables.hpp; the reference in docs/campaigns.md is made from
// them):
//
//   [campaign]   what the campaign is; [ensemble] the runs and the method (ensemble.method, a row of
//                the method table, methods/method_table.hpp); [output] the stored histories;
//   [scene]      a file, inline [scene.<table>] tables and overrides: the base scene;
//   [[dispersion]] the dispersed keys (apply: absolute = the drawn value; relative = nominal *
//                (1 + drawn); offset = nominal + drawn);
//   [ensemble.<method>] and the root tables a method claims ([failure]; a composite's [sweep]): the
//                method's own options, read and checked by its row (method_options.hpp).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "campaign/method_options.hpp"
#include "io/scene_toml.hpp"
#include "sampling/sampling.hpp"
#include "sim/scene.hpp"

namespace truss::campaign {

using sampling::DistributionKind;
using sampling::SamplingMethod;

enum class Per { run, bay, frame };
enum class Apply { absolute, relative, offset };
const char* to_string(Per p);      // as campaign files write them: "run", "bay", "frame"
const char* to_string(Apply a);    // "absolute", "relative", "offset"

struct DispersionOptions {
  std::string key;                  // scene key, "table.key"
  Per per = Per::run;               // one draw per run, or one per bay / per frame
  Apply apply = Apply::relative;    // how the draw changes the nominal value
  DistributionKind distribution = DistributionKind::normal;  // parsed from its name (sampling::kDistributionNames)
  double mean = 0, std = 0, lower = 0, upper = 0, mu = 0, sigma = 0;
  std::vector<double> values, weights;  // discrete table
  int line = 0;                     // line of the [[dispersion]] entry, for messages
};

struct EnsembleOptions {
  std::int64_t n_runs = 100;                 // number of deployments
  std::uint64_t master_seed = 1;             // with the run index, the only source of randomness
  SamplingMethod sampling = SamplingMethod::monte_carlo;  // parsed from its name (sampling::kSamplingNames)
  double max_run_wall_time_s = 60.0;         // a run longer than this is stopped and recorded
  // The method (method_options.hpp): its row's name and its own options. Set by the parser;
  // options built in code set it from a method table's row.
  MethodChoice method;
};

struct OutputOptions {
  std::vector<std::int64_t> history_runs;    // runs whose time histories are stored; none by default
  double history_step_s = 0.01;              // their sample step: 100 Hz resolves the lock transients
};

struct CampaignOptions {
  std::string name = "campaign";
  std::string description;
  EnsembleOptions ensemble;
  std::string scene_file;                     // as written (may be empty: Table 1 defaults)
  OutputOptions output;
  std::vector<io::SceneSetting> scene_settings;  // inline tables, overrides and --set, in order
  sim::SceneOptions base;                     // the resolved base scene
  std::vector<DispersionOptions> dispersions;
  std::vector<std::string> warnings;          // plausibility warnings of the base scene (not written back)
  // Every rule of a campaign, in one place: empty, or "field: reason" naming the first field that
  // breaks one ("ensemble.n_runs: ...", "output.history_runs: ...", "dispersion[2].per: ...").
  // The parser calls it once on what it built and reports the field's file and line; options built
  // in code are checked by their builder. The base scene is not checked here: it is validated
  // where it is built (the scene parser, or sim::SceneOptions::validate by a builder in code).
  std::string validate() const;
};

// Reads, parses and validates a campaign file; `overrides` are --set arguments ("table.key=value"
// for campaign keys such as ensemble.n_runs, or a base-scene key as truss-sim takes it,
// "mast.n_bays=12", also written "scene.mast.n_bays=12"); `methods`: the rows ensemble.method
// names (methods::builtin_methods(); methods::parse_campaign_file passes it).
// Throws io::InputError with a message naming the file, key and line (or the --set).
CampaignOptions parse_campaign_file(const std::string& path, const MethodCatalog& methods,
                                    const std::vector<std::string>& overrides = {});

// Same, for campaign text in memory; source_name names it in messages, and a relative scene.file is
// resolved against base_dir.
CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name,
                                    const std::string& base_dir, const MethodCatalog& methods,
                                    const std::vector<std::string>& overrides = {});

// The campaign with everything resolved, as TOML that parse_campaign_text reads back to the same
// options: the base scene inline (every key), every dispersion with all its parameters.
std::string resolved_campaign_toml(const CampaignOptions& c);

// The most runs the campaign can make (its method's; ensemble.n_runs unless the method runs more,
// as stop's max_runs, or a sweep that many at each value it can run): what memory and disk are
// checked for.
inline std::int64_t calc_max_runs(const CampaignOptions& c) { return c.ensemble.method.options().calc_max_runs(c); }

// The rules of a fixed design over ensemble.n_runs and ensemble.sampling (a Saltelli design's
// blocks, each plan's limits), for the methods whose points are the design's: "" or "field: reason".
std::string validate_sampling(const CampaignOptions& c);
// The unit of the float64 run field `name` (RunResult, io::run_result_fields), or "" if none.
std::string find_run_column_unit(const std::string& name);

// Runs per Saltelli block: A, B and one AB matrix per dispersion (a dispersion is one factor).
inline std::int64_t saltelli_block_runs(const CampaignOptions& c) {
  return static_cast<std::int64_t>(c.dispersions.size()) + 2;
}

// Keys that can be dispersed, and how: per-bay keys (strut and diagonal parameters), per-frame
// keys (frame side and mass), or once per run (everything numeric).
bool is_bay_key(const std::string& key);
bool is_frame_key(const std::string& key);
bool is_dispersible_key(const std::string& key);

}  // namespace truss::campaign
