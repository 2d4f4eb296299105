#include "methods/subset_method.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"
#include "campaign/method_input.hpp"
#include "io/h5_util.hpp"
#include "results/result_store.hpp"
#include "sim/scene_keys.hpp"

namespace truss::methods {

SubsetMethod::SubsetMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      opt_(ctx.options.ensemble.method.as<SubsetMethodOptions>()),
      sim_opt_(opt_.calc_sim_options(ctx.options)),
      margins_(opt_.failure) {
  if (ctx_.record.find_output(opt_.failure.column) < 0)
    throw std::logic_error(fmt::format("subset: {} is not a float64 output of the record", opt_.failure.column));
}

Proposal SubsetMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) {
    sim_.emplace(sim_opt_);
  } else {
    if (!sim_ || sim_->done()) return {};
    sim_->add_margins(margins_.add(previous));
    if (sim_->done()) return {};
  }
  const sampling::SubsetRound& r = sim_->round();
  const std::int64_t first = round == 0 ? 0 : previous.first_run + static_cast<std::int64_t>(previous.status.size());
  if (r.first_evaluation != first)  // the run index is the evaluation ordinal: failure samples name their runs
    throw std::logic_error(fmt::format("subset: round {} starts at evaluation {}, run {}", round, r.first_evaluation,
                                       first));
  return {r.n_points, r.encode()};
}

void SubsetMethod::calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const {
  std::shared_ptr<const sampling::SubsetRound> r;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!decoded_ || decoded_->index != plan.round)
      decoded_ =
          std::make_shared<const sampling::SubsetRound>(sampling::SubsetRound::decode(plan.state, sim_opt_.dims));
    r = decoded_;
  }
  sampling::calc_round_uniforms(sim_opt_, *r, run - plan.first_run, u);
}

sampling::SubsetOptions SubsetMethodOptions::calc_sim_options(const campaign::CampaignOptions& c) const {
  const SubsetSettings& s = subset;
  sampling::SubsetOptions o;
  o.dims = campaign::calc_layout(c).total;
  o.n_per_level = s.n_per_level;
  o.p0 = s.p0;
  o.max_levels = s.max_levels;
  o.proposal_half_width = s.proposal_half_width;
  o.proposal = s.proposal;
  o.seed = c.ensemble.master_seed;
  return o;
}

std::int64_t SubsetMethodOptions::calc_n_runs(const campaign::CampaignOptions& c) const {
  const sampling::SubsetOptions s = calc_sim_options(c);
  return s.validate().empty() ? s.max_evaluations() : 0;
}

std::string SubsetMethodOptions::describe_max_runs(const campaign::CampaignOptions& c) const {
  return fmt::format("ensemble.subset.n_per_level = {} (max_levels = {}: at most {} runs)", subset.n_per_level,
                     subset.max_levels, c.ensemble.n_runs);
}

namespace {
bool uses_half_width(const SubsetMethodOptions& o) {
  return o.subset.proposal == sampling::SubsetProposal::modified_metropolis;
}
}  // namespace

const campaign::OptionTable<SubsetMethodOptions>& SubsetMethodOptions::table() {
  using S = SubsetMethodOptions;
  static const campaign::OptionTable<S> t{
      "ensemble.subset", "subset simulation of the [failure] event's probability: it chooses its runs", {
          TRUSS_OPTION_INT(S, "n_per_level", subset.n_per_level, "1", campaign::kAnyNumber,
                           "N: samples per level (N p0 a whole number of chains)"),
          TRUSS_OPTION_REAL(S, "p0", subset.p0, "1", campaign::kAnyNumber,
                            "the share of a level kept as the next one's seeds, in (0, 0.5]"),
          TRUSS_OPTION_INT(S, "max_levels", subset.max_levels, "1", campaign::closed_range(1, 1000),
                           "levels at most: the run cap N + (max_levels - 1) N (1 - p0)"),
          TRUSS_OPTION_CHOICE(S, "proposal", subset.proposal,
                              "the Markov step: modified Metropolis (uniform, per dimension) or adaptive "
                              "conditional sampling (Papaioannou et al. 2015)",
                              campaign::choice_names(sampling::kSubsetProposalNames)),
          campaign::written_if(
              TRUSS_OPTION_REAL(S, "proposal_half_width", subset.proposal_half_width, "1", campaign::kAnyNumber,
                                "modified Metropolis: uniform on +- this many standard deviations, in [0.001, 10]"),
              &uses_half_width),
          TRUSS_OPTION_CHOICE(S, "interval_cov", subset.interval_cov,
                              "the CoV of the lognormal interval: the full-correlation bound, or the lag-1 CoV "
                              "blended with it by the surviving lineages",
                              campaign::choice_names(sampling::kSubsetIntervalCovNames)),
      }};
  return t;
}

std::unique_ptr<campaign::MethodOptions> SubsetMethodOptions::parse(const campaign::MethodInput& in) {
  auto o = std::make_unique<SubsetMethodOptions>();
  campaign::read_method_table(in, table(), *o);
  if (const toml::node* a = in.table != nullptr ? in.table->get("proposal_half_width") : nullptr;
      a != nullptr && !uses_half_width(*o))
    in.source.fail(a, fmt::format("{}proposal_half_width: the step of proposal = \"modified_metropolis\"; {} "
                                  "adapts its own spread: remove it, or set proposal = \"modified_metropolis\"",
                                  in.prefix, sampling::to_string(o->subset.proposal)));
  campaign::read_failure_event(in, o->failure);
  return o;
}

std::string SubsetMethodOptions::validate(const campaign::CampaignOptions& o) const {
  const FailureOptions& f = failure;
  if (o.ensemble.sampling != sampling::SamplingMethod::monte_carlo)
    return "ensemble.sampling: method = \"subset\" draws its own points (standard normal, then Markov chains): "
           "remove sampling";
  if (o.dispersions.empty()) return "ensemble.method: subset simulation needs at least one [[dispersion]]";
  if (const std::string e = calc_sim_options(o).validate(); !e.empty()) return "ensemble.subset." + e;
  if (f.kind == FailureKind::none)
    return "failure: method = \"subset\" needs a [failure] table: margin = \"rail_margin_m\", or column = "
           "\"peak_drive_force_N\", above = 3.5, unit = \"N\"";
  return campaign::check_option_ranges(table(), *this, "ensemble.subset.");
}

std::string SubsetMethodOptions::to_toml() const {
  return "[ensemble.subset]\n" + campaign::write_options(table(), *this) + "\n" + campaign::failure_toml(failure);
}

std::string find_subset_distrust(const sampling::SubsetSummary& s, std::int64_t unusable, std::int64_t runs) {
  if (std::string why = find_unusable_reason(unusable, runs); !why.empty()) return why;
  return sampling::find_untrusted_reason(s);
}

std::optional<FailureEstimate> SubsetMethod::calc_failure_estimate(double confidence) const {
  if (!sim_) return FailureEstimate{};
  const sampling::SubsetSummary s = sim_->calc_summary();
  FailureEstimate e;
  e.cov = s.calc_interval_cov(opt_.subset.interval_cov);
  e.bounds = sampling::calc_lognormal_bounds(s.p, e.cov, confidence);
  e.bounds.p = s.p;
  e.runs = margins_.runs();
  e.status = sampling::to_string(s.status);
  e.message = s.message;
  e.nearest_margin = margins_.nearest_margin();
  std::int64_t runs = 0;
  for (const sampling::SubsetLevel& l : s.levels) {
    runs += l.runs;
    e.unusable += l.unusable;
  }
  e.untrusted = find_subset_distrust(s, e.unusable, runs);
  return e;
}

namespace {

using namespace io::h5;

void write_levels(hid_t g, const sampling::SubsetSummary& s, const char* unit) {
  Handle lv = create_group(g, "levels");
  const std::size_t n = s.levels.size();
  std::vector<double> threshold(n), prob(n), acc(n), gamma(n), cov(n);
  std::vector<std::int64_t> runs(n), unusable(n), ties(n);
  for (std::size_t k = 0; k < n; ++k) {
    const sampling::SubsetLevel& l = s.levels[k];
    threshold[k] = l.threshold;
    prob[k] = l.probability;
    acc[k] = l.acceptance();
    gamma[k] = l.gamma;
    cov[k] = l.cov;
    runs[k] = l.runs;
    unusable[k] = l.unusable;
    ties[k] = l.ties;
  }
  write_array(lv.get(), "threshold", unit, threshold.data(), n);
  write_array(lv.get(), "probability", "1", prob.data(), n);
  write_array(lv.get(), "acceptance", "1", acc.data(), n);
  write_array(lv.get(), "gamma", "1", gamma.data(), n);
  write_array(lv.get(), "cov", "1", cov.data(), n);
  write_array(lv.get(), "runs", "1", runs.data(), n);
  write_array(lv.get(), "unusable", "1", unusable.data(), n);
  write_array(lv.get(), "ties", "1", ties.data(), n);
}

}  // namespace

void SubsetMethod::write_results(const ResultsPlace& place) const {
  if (!sim_) return;
  const sampling::SubsetSummary s = sim_->calc_summary();
  const FailureOptions& f = opt_.failure;
  const std::string unit = campaign::find_run_column_unit(f.column);
  Handle g = create_group(place.group, "subset");
  write_string_attribute(g.get(), "status", sampling::to_string(s.status));
  write_string_attribute(g.get(), "message", s.message);
  write_failure_attributes(g.get(), f, "margin_units");
  write_int_attribute(g.get(), "n_per_level", sim_opt_.n_per_level);
  write_double_attribute(g.get(), "p0", sim_opt_.p0);
  write_int_attribute(g.get(), "max_levels", sim_opt_.max_levels);
  write_string_attribute(g.get(), "proposal", sampling::to_string(opt_.subset.proposal));
  write_string_attribute(g.get(), "interval_cov", sampling::to_string(opt_.subset.interval_cov));
  const double cov = s.calc_interval_cov(opt_.subset.interval_cov);
  write_scalar(g.get(), "p", "1", s.p);
  write_scalar(g.get(), "cov", "1", s.cov);
  write_scalar(g.get(), "cov_lineage", "1", s.cov_lineage);
  write_scalar(g.get(), "cov_bound", "1", s.cov_bound);
  write_scalar(g.get(), "cov_lag1", "1", s.cov_lag1);
  write_scalar(g.get(), "cov_interval", "1", s.cov_interval);
  write_scalar(g.get(), "beta", "1", s.beta);
  write_scalar(g.get(), "runs", "1", s.runs);
  write_scalar(g.get(), "lineages", "1", s.lineages);
  write_scalar(g.get(), "lineage_groups", "1", s.lineage_groups);
  // Crude Monte Carlo runs for an interval as narrow as the estimate's (interval_cov): (1 - p) / (p cov^2).
  write_scalar(g.get(), "crude_mc_runs", "1", (1.0 - s.p) / (s.p * cov * cov));
  write_levels(g.get(), s, unit.c_str());
  write_failure_samples(g.get(), place, unit);
}

std::string SubsetMethod::calc_result_failure() const {
  if (!sim_) return {};
  const sampling::SubsetSummary s = sim_->calc_summary();
  if (s.status != sampling::SubsetStatus::chains_stuck) return {};
  return fmt::format("subset simulation has no estimate ({}): {}", sampling::to_string(s.status), s.message);
}

std::string SubsetMethod::calc_result_text() const {
  if (!sim_) return {};
  const sampling::SubsetSummary s = sim_->calc_summary();
  const FailureOptions& f = opt_.failure;
  const std::string unit = campaign::find_run_column_unit(f.column);
  const bool above = f.kind == FailureKind::above;
  std::string t = fmt::format("[truss-campaign] subset simulation of P({} {} {} {}): {} ({})\n", f.column,
                              above ? ">=" : "<=", f.kind == FailureKind::margin ? 0.0 : f.threshold, unit,
                              sampling::to_string(s.status), s.message);
  // With no failing sample (p = 0) there is no CoV to match: say so rather than print inf and NaN.
  const double cov = s.calc_interval_cov(opt_.subset.interval_cov);
  const std::string crude =
      s.p > 0.0 ? fmt::format("crude Monte Carlo would need {:.3g} runs for an interval as narrow",
                              (1.0 - s.p) / (s.p * cov * cov))
                : std::string("no failing sample");
  t += fmt::format("[truss-campaign]   p = {:.4g}, CoV {:.3g} ({}, the interval's; bound {:.3g}, lineage {:.3g}, Au & "
                   "Beck {:.3g}), beta = {:.4g}, {} runs in {} levels, {} ({})\n", s.p, cov,
                   sampling::to_string(opt_.subset.interval_cov), s.cov_bound, s.cov_lineage, s.cov, s.beta, s.runs,
                   s.levels.size(), sampling::to_string(opt_.subset.proposal), crude);
  for (std::size_t k = 0; k < s.levels.size(); ++k) {
    const std::string acceptance = k == 0 ? std::string("- (independent draws)")
                                          : fmt::format("{:.3g}", s.levels[k].acceptance());
    t += fmt::format("[truss-campaign]   level {}: margin <= {:.6g} {} in {:.3g} of its samples, {} runs, "
                     "acceptance {}\n", k, s.levels[k].threshold, unit, s.levels[k].probability,
                     s.levels[k].runs, acceptance);
  }
  return t;
}

std::string SubsetMethod::progress_stage() const {
  if (!sim_ || sim_->done()) return {};
  const sampling::SubsetRound& r = sim_->round();
  if (r.level == 0) return "level 0 (independent draws)";
  // A chain's longest walk.
  const std::int64_t steps = (sim_opt_.n_per_level + sim_opt_.n_chains() - 1) / sim_opt_.n_chains() - 1;
  return fmt::format("level {} (margin <= {:.4g} {}), Markov step {} of {}", r.level, r.threshold,
                     campaign::find_run_column_unit(opt_.failure.column), r.step, steps);
}

// The failing points of the last level with their inputs as /runs/inputs has them (rows x width),
// each with the base scene's value as its attribute `nominal` (the design-point table).
void SubsetMethod::write_failure_samples(hid_t group, const ResultsPlace& place, const std::string& unit) const {
  const hid_t file = place.file;
  const std::vector<sampling::SubsetSample> fs = sim_->calc_failure_samples();
  const std::size_t n = fs.size(), d = static_cast<std::size_t>(sim_opt_.dims);
  Handle h = create_group(group, "failure_samples");
  std::vector<std::int64_t> run(n);
  std::vector<double> margin(n), z(n * d);
  for (std::size_t i = 0; i < n; ++i) {
    run[i] = place.find_row(fs[i].evaluation);
    margin[i] = fs[i].margin;
    std::copy(fs[i].z.begin(), fs[i].z.end(), z.begin() + static_cast<std::ptrdiff_t>(i * d));
  }
  write_array(h.get(), "run_index", "1", run.data(), n);
  write_array(h.get(), "margin", unit.c_str(), margin.data(), n);
  write_array(h.get(), "z", "1", z.data(), n, d);
  Handle in = create_group(h.get(), "inputs");
  for (const campaign::Field& f : ctx_.record.fields()) {
    if (f.group != campaign::Group::inputs) continue;
    const auto w = static_cast<std::size_t>(f.width);
    const std::string path = std::string(campaign::group_path(f.group)) + "/" + f.name;
    const std::vector<double> rows = results::read_f64_rows(file, path, run);
    write_array(in.get(), f.name, f.units.c_str(), rows.data(), n, f.scale == campaign::Scale::none ? 0 : w);
    const sim::SceneKey* key = sim::find_scene_key(f.name);
    Handle ds(H5Dopen2(in.get(), f.name.c_str(), H5P_DEFAULT), H5Dclose, "open " + f.name);
    if (key != nullptr && key->get_real != nullptr)
      write_double_attribute(ds.get(), "nominal", key->get_real(ctx_.options.base));
    else if (key != nullptr && key->get_int != nullptr)
      write_double_attribute(ds.get(), "nominal", static_cast<double>(key->get_int(ctx_.options.base)));
  }
}

}  // namespace truss::methods
