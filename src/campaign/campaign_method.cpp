// How a campaign chooses its runs, as its file says (campaign.hpp): ensemble.method, the subset
// simulation's settings [ensemble.subset] and its failure event [failure]; their one set of rules
// (validate_method, part of CampaignOptions::validate) and their resolved TOML.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"
#include "campaign/toml_read.hpp"
#include "io/json_summary.hpp"

namespace truss::campaign {

sampling::SubsetOptions calc_subset_options(const CampaignOptions& c) {
  const SubsetSettings& s = c.ensemble.subset;
  sampling::SubsetOptions o;
  o.dims = calc_layout(c).dispersion_dims();
  o.n_per_level = s.n_per_level;
  o.p0 = s.p0;
  o.max_levels = s.max_levels;
  o.proposal_half_width = s.proposal_half_width;
  o.seed = c.ensemble.master_seed;
  return o;
}

std::string find_run_column_unit(const std::string& name) {
  if (name == "wall_time_s") return {};  // the record's run_wall_time_s: not an output
  const sim::RunResult none;
  for (const io::RunField& f : io::run_result_fields())
    if (name == f.name && std::holds_alternative<double>(f.get(none))) return f.units;
  return {};
}

namespace detail {

void parse_subset_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  SubsetSettings& s = o.ensemble.subset;
  for (const auto& [k, v] : t) {
    const std::string key = "ensemble.subset." + std::string(k.str());
    if (k == "n_per_level") s.n_per_level = get_integer(c, v, key);
    else if (k == "p0") s.p0 = get_number(c, v, key);
    else if (k == "max_levels") {
      const std::int64_t m = get_integer(c, v, key);
      if (m < 1 || m > 1000) c.fail(&v, fmt::format("{}: {} (must lie in [1, 1000])", key, m));
      s.max_levels = static_cast<int>(m);
    } else if (k == "proposal_half_width") s.proposal_half_width = get_number(c, v, key);
    else c.fail(&v, fmt::format("unknown key '{}' (known: ensemble.subset.n_per_level, ensemble.subset.p0, "
                                "ensemble.subset.max_levels, ensemble.subset.proposal_half_width)", key));
  }
}

void parse_stop_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  sampling::StopRule& r = o.ensemble.stop_rule;
  o.ensemble.stop = true;
  const std::vector<std::string> targets(std::begin(sampling::kStopTargetNames), std::end(sampling::kStopTargetNames));
  for (const auto& [k, v] : t) {
    const std::string key = "ensemble.stop." + std::string(k.str());
    if (k == "target") {
      const std::string s = get_string(c, v, key, targets);
      r.target = static_cast<sampling::StopTarget>(std::find(targets.begin(), targets.end(), s) - targets.begin());
    } else if (k == "output") o.ensemble.stop_output = get_string(c, v, key);
    else if (k == "level") r.level = get_number(c, v, key);
    else if (k == "width") r.width = get_number(c, v, key);
    else if (k == "confidence") r.confidence = get_number(c, v, key);
    else if (k == "max_runs") r.max_runs = get_integer(c, v, key);
    else c.fail(&v, fmt::format("unknown key '{}' (known: ensemble.stop.target, output, level, width, confidence, "
                                "max_runs)", key));
  }
}

void parse_failure_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  FailureOptions& f = o.failure;
  f.line = static_cast<int>(t.source().begin.line);
  const toml::node *margin = t.get("margin"), *column = t.get("column"), *above = t.get("above"),
                   *below = t.get("below"), *unit = t.get("unit");
  for (const auto& [k, v] : t)
    if (k != "margin" && k != "column" && k != "above" && k != "below" && k != "unit")
      c.fail(&v, fmt::format("unknown key 'failure.{}' (known: failure.margin, failure.column, failure.above, "
                             "failure.below, failure.unit)", k.str()));
  if ((margin != nullptr) == (column != nullptr))
    c.fail(margin ? margin : column ? column : &t,
           "failure: give either margin = \"<column>\" (failed when <= 0, e.g. \"rail_margin_m\") or column = "
           "\"<column>\" with above = or below = a threshold and unit = the column's unit");
  if (margin) {
    if (above || below || unit)
      c.fail(above ? above : below ? below : unit,
             "failure: a margin fails at 0; above, below and unit go with column");
    f.kind = FailureKind::margin;
    f.column = get_string(c, *margin, "failure.margin");
    return;
  }
  f.column = get_string(c, *column, "failure.column");
  if ((above != nullptr) == (below != nullptr))
    c.fail(above ? above : column, "failure: a column fails above or below a threshold: give one of above, below");
  f.kind = above ? FailureKind::above : FailureKind::below;
  f.threshold = get_number(c, above ? *above : *below, above ? "failure.above" : "failure.below");
  if (!std::isfinite(f.threshold)) c.fail(above ? above : below, "failure: the threshold must be finite");
  if (!unit) c.fail(column, fmt::format("failure.unit: missing: say the threshold's unit (the column {} is in {})",
                                        f.column, find_run_column_unit(f.column)));
  f.unit = get_string(c, *unit, "failure.unit");
}

void derive_subset_runs(const Ctx& c, const toml::table& root, CampaignOptions& o) {
  if (o.ensemble.method != EnsembleMethod::subset) return;
  if (const toml::node* n = root.at_path("ensemble.n_runs").node())
    c.fail(n, "ensemble.n_runs: method = \"subset\" chooses its runs ([ensemble.subset] n_per_level, p0 and "
              "max_levels cap them); remove n_runs");
  const sampling::SubsetOptions s = calc_subset_options(o);
  if (s.validate().empty()) o.ensemble.n_runs = s.max_evaluations();
}

// The rules of [ensemble.stop]: a Monte Carlo design (its points extend run by run), a rule that
// can be met within max_runs (StopRule::validate), a percentile of a float64 column.
std::string validate_stop(const CampaignOptions& o) {
  const EnsembleOptions& e = o.ensemble;
  if (e.method == EnsembleMethod::subset)
    return "ensemble.stop: method = \"subset\" has its own end; remove [ensemble.stop]";
  if (e.sampling != SamplingMethod::monte_carlo)
    return fmt::format("ensemble.sampling: [ensemble.stop] adds runs round by round, which only Monte Carlo points "
                       "allow (\"{}\" fixes its design for n_runs)", to_string(e.sampling));
  if (const std::string err = e.stop_rule.validate(); !err.empty()) return "ensemble.stop." + err;
  if (e.n_runs > e.stop_rule.max_runs)
    return fmt::format("ensemble.stop.max_runs: {} is below the first round's ensemble.n_runs = {}",
                       e.stop_rule.max_runs, e.n_runs);
  const bool percentile = e.stop_rule.target == sampling::StopTarget::percentile_bound;
  if (percentile && find_run_column_unit(e.stop_output).empty())
    return fmt::format("ensemble.stop.output: \"{}\" is not a float64 column of /runs (e.g. peak_drive_torque_Nm)",
                       e.stop_output);
  if (!percentile && !e.stop_output.empty())
    return "ensemble.stop.output: the probability targets count the runs that are not ok; output goes with "
           "target = \"percentile_bound\"";
  return {};
}

std::string validate_method(const CampaignOptions& o) {
  if (o.ensemble.stop)
    if (std::string e = validate_stop(o); !e.empty()) return e;
  const FailureOptions& f = o.failure;
  if (o.ensemble.method != EnsembleMethod::subset)
    return f.kind == FailureKind::none || o.sweep.active
               ? ""
               : "failure: only ensemble.method = \"subset\" reads [failure] (or a [sweep], at each of its values)";
  if (o.ensemble.sampling != SamplingMethod::monte_carlo)
    return "ensemble.sampling: method = \"subset\" draws its own points (standard normal, then Markov chains): "
           "remove sampling";
  if (o.dispersions.empty()) return "ensemble.method: subset simulation needs at least one [[dispersion]]";
  if (const std::string e = calc_subset_options(o).validate(); !e.empty()) return "ensemble.subset." + e;
  if (f.kind == FailureKind::none)
    return "failure: method = \"subset\" needs a [failure] table: margin = \"rail_margin_m\", or column = "
           "\"peak_drive_force_N\", above = 3.5, unit = \"N\"";
  const std::string field = f.kind == FailureKind::margin ? "failure.margin" : "failure.column";
  const std::string unit = find_run_column_unit(f.column);
  if (unit.empty())
    return fmt::format("{}: \"{}\" is not a float64 column of /runs (a RunResult output, e.g. rail_margin_m, "
                       "peak_drive_force_N)", field, f.column);
  if (f.kind != FailureKind::margin && f.unit != unit)
    return fmt::format("failure.unit: \"{}\", but {} is in \"{}\" (give the threshold in the column's unit)", f.unit,
                       f.column, unit);
  return {};
}

std::string method_toml(const CampaignOptions& o) {
  std::string t;
  if (o.ensemble.stop) {
    const sampling::StopRule& r = o.ensemble.stop_rule;
    t = fmt::format("[ensemble.stop]\ntarget = \"{}\"\n", sampling::to_string(r.target));
    if (!o.ensemble.stop_output.empty()) t += fmt::format("output = \"{}\"\n", o.ensemble.stop_output);
    t += fmt::format("level = {}\nwidth = {}\nconfidence = {}\nmax_runs = {}\n\n", r.level, r.width, r.confidence,
                     r.max_runs);
  } else if (o.ensemble.method == EnsembleMethod::subset) {
    const SubsetSettings& s = o.ensemble.subset;
    t = fmt::format("[ensemble.subset]\nn_per_level = {}\np0 = {}\nmax_levels = {}\nproposal_half_width = {}\n\n",
                    s.n_per_level, s.p0, s.max_levels, s.proposal_half_width);
  }
  const FailureOptions& f = o.failure;  // subset simulation's event, or a sweep's
  if (f.kind == FailureKind::none) return t;
  if (f.kind == FailureKind::margin) return t + fmt::format("[failure]\nmargin = \"{}\"\n\n", f.column);
  return t + fmt::format("[failure]\ncolumn = \"{}\"\n{} = {}\nunit = \"{}\"\n\n", f.column,
                         f.kind == FailureKind::above ? "above" : "below", f.threshold, f.unit);
}

}  // namespace detail
}  // namespace truss::campaign
