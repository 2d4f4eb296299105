#include "methods/subset_method.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"
#include "campaign/toml_read.hpp"
#include "io/h5_util.hpp"
#include "results/result_store.hpp"
#include "sim/scene_keys.hpp"

namespace truss::methods {

SubsetMethod::SubsetMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      opt_(ctx.options.ensemble.method.as<SubsetMethodOptions>()),
      sim_opt_(opt_.calc_sim_options(ctx.options)) {
  if (ctx_.record.find_output(opt_.failure.column) < 0)
    throw std::logic_error(fmt::format("subset: {} is not a float64 output of the record", opt_.failure.column));
}

std::vector<double> SubsetMethod::calc_margins(const FailureOptions& f, const RoundRecords& r) {
  const std::vector<double>& y = r.outputs.at(0);
  std::vector<double> m(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double v = f.kind == FailureKind::above   ? f.threshold - y[i]
                     : f.kind == FailureKind::below ? y[i] - f.threshold
                                                    : y[i];
    const bool says = r.status[i] == static_cast<std::int8_t>(sim::RunStatus::ok) || v <= 0.0;
    m[i] = says ? v : std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

Proposal SubsetMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) {
    sim_.emplace(sim_opt_);
  } else {
    if (!sim_ || sim_->done()) return {};
    sim_->add_margins(calc_margins(opt_.failure, previous));
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

using campaign::detail::Ctx;
using campaign::detail::get_integer;
using campaign::detail::get_number;

void parse_subset_table(const Ctx& c, const toml::table& t, const std::string& prefix, SubsetSettings& s) {
  for (const auto& [k, v] : t) {
    const std::string key = prefix + std::string(k.str());
    if (k == "n_per_level") s.n_per_level = get_integer(c, v, key);
    else if (k == "p0") s.p0 = get_number(c, v, key);
    else if (k == "max_levels") {
      const std::int64_t m = get_integer(c, v, key);
      if (m < 1 || m > 1000) c.fail(&v, fmt::format("{}: {} (must lie in [1, 1000])", key, m));
      s.max_levels = static_cast<int>(m);
    } else if (k == "proposal_half_width") s.proposal_half_width = get_number(c, v, key);
    else c.fail(&v, campaign::detail::unknown_key_text(key, fmt::format("{0}n_per_level, {0}p0, {0}max_levels, "
                                                                        "{0}proposal_half_width", prefix)));
  }
}

}  // namespace

std::unique_ptr<campaign::MethodOptions> SubsetMethodOptions::parse(const campaign::MethodInput& in) {
  auto o = std::make_unique<SubsetMethodOptions>();
  if (in.table != nullptr) parse_subset_table(in.ctx, *in.table, in.prefix, o->subset);
  if (const toml::table* f = in.root["failure"].as_table())
    campaign::detail::parse_failure_table(in.ctx, *f, o->failure);
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
  return campaign::validate_failure_column(f);
}

std::string SubsetMethodOptions::to_toml() const {
  const SubsetSettings& s = subset;
  std::string t = fmt::format("[ensemble.subset]\nn_per_level = {}\np0 = {}\nmax_levels = {}\n"
                              "proposal_half_width = {}\n\n",
                              s.n_per_level, s.p0, s.max_levels, s.proposal_half_width);
  return t + campaign::failure_toml(failure);
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

void SubsetMethod::write_results(hid_t file, std::int64_t n_runs) const {
  if (!sim_) return;
  const sampling::SubsetSummary s = sim_->calc_summary();
  const FailureOptions& f = opt_.failure;
  const std::string unit = campaign::find_run_column_unit(f.column);
  Handle g = create_group(file, "subset");
  write_string_attribute(g.get(), "status", sampling::to_string(s.status));
  write_string_attribute(g.get(), "message", s.message);
  write_string_attribute(g.get(), "failure_column", f.column);
  write_string_attribute(g.get(), "failure_kind", f.kind == FailureKind::margin  ? "margin"
                                                  : f.kind == FailureKind::above ? "above"
                                                                                           : "below");
  write_double_attribute(g.get(), "failure_threshold", f.kind == FailureKind::margin ? 0.0 : f.threshold);
  write_string_attribute(g.get(), "margin_units", unit);
  write_int_attribute(g.get(), "n_per_level", sim_opt_.n_per_level);
  write_double_attribute(g.get(), "p0", sim_opt_.p0);
  write_int_attribute(g.get(), "max_levels", sim_opt_.max_levels);
  write_scalar(g.get(), "p", "1", s.p);
  write_scalar(g.get(), "cov", "1", s.cov);
  write_scalar(g.get(), "cov_lineage", "1", s.cov_lineage);
  write_scalar(g.get(), "cov_bound", "1", s.cov_bound);
  write_scalar(g.get(), "beta", "1", s.beta);
  write_scalar(g.get(), "runs", "1", s.runs);
  write_scalar(g.get(), "lineages", "1", s.lineages);
  // Crude Monte Carlo runs for an interval as narrow as the estimate's (cov_bound): (1 - p) / (p cov^2).
  write_scalar(g.get(), "crude_mc_runs", "1", (1.0 - s.p) / (s.p * s.cov_bound * s.cov_bound));
  write_levels(g.get(), s, unit.c_str());
  write_failure_samples(g.get(), file, n_runs, unit);
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
  const std::string crude =
      s.p > 0.0 ? fmt::format("crude Monte Carlo would need {:.3g} runs for an interval as narrow",
                              (1.0 - s.p) / (s.p * s.cov_bound * s.cov_bound))
                : std::string("no failing sample");
  t += fmt::format("[truss-campaign]   p = {:.4g}, CoV {:.3g} (the bound the interval uses; lineage {:.3g}, Au & Beck "
                   "{:.3g}), beta = {:.4g}, {} runs in {} levels ({})\n", s.p, s.cov_bound, s.cov_lineage, s.cov,
                   s.beta, s.runs, s.levels.size(), crude);
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
void SubsetMethod::write_failure_samples(hid_t group, hid_t file, std::int64_t n_runs, const std::string& unit) const {
  const std::vector<sampling::SubsetSample> fs = sim_->calc_failure_samples();
  const std::size_t n = fs.size(), d = static_cast<std::size_t>(sim_opt_.dims);
  Handle h = create_group(group, "failure_samples");
  std::vector<std::int64_t> run(n);
  std::vector<double> margin(n), z(n * d);
  for (std::size_t i = 0; i < n; ++i) {
    run[i] = fs[i].evaluation;
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
    std::vector<std::vector<double>> cols;
    if (f.scale == campaign::Scale::none) cols.push_back(results::read_f64_column(file, path, n_runs));
    else cols = results::read_f64_columns(file, path, n_runs, f.width, 0, f.width, 4096);
    std::vector<double> rows(n * w);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < w; ++j) rows[i * w + j] = cols[j][static_cast<std::size_t>(run[i])];
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
