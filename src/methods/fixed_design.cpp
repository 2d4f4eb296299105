#include "methods/fixed_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/method_input.hpp"
#include "io/h5_util.hpp"
#include "results/result_store.hpp"

namespace truss::methods {

namespace {

sampling::SamplePlan make_plan(const campaign::CampaignContext& ctx) {
  const campaign::CampaignOptions& c = ctx.options;
  const campaign::DimensionLayout& L = ctx.dims;
  if (c.ensemble.sampling != sampling::SamplingMethod::saltelli)
    return {c.ensemble.sampling, c.ensemble.n_runs, std::max(1, L.total), c.ensemble.master_seed};
  return {sampling::SamplingMethod::saltelli, c.ensemble.n_runs, L.total, c.ensemble.master_seed, L.count};
}

constexpr std::uint64_t kBootstrapTag = 0x53454e53495449ULL;  // "SENSITI": bootstrap seed offset

}  // namespace

std::unique_ptr<campaign::MethodOptions> DesignOptions::parse(const campaign::MethodInput& in) {
  if (in.table != nullptr && !in.table->empty())  // [ensemble.design] has no keys
    in.source.fail(&in.table->cbegin()->second,
                   fmt::format("unknown key '{}{}' (the design's keys are ensemble.n_runs and ensemble.sampling)",
                               in.prefix, in.table->cbegin()->first.str()));
  auto o = std::make_unique<DesignOptions>();
  campaign::read_failure_event(in, o->failure);
  return o;
}

std::string DesignOptions::validate(const campaign::CampaignOptions& c) const {
  if (failure.kind != campaign::FailureKind::none && c.ensemble.sampling != sampling::SamplingMethod::monte_carlo)
    return fmt::format("ensemble.sampling: \"{}\" gives no binomial interval of a probability: the [failure] "
                       "event's probability is the share of failing Monte Carlo runs (ensemble.sampling = "
                       "\"monte_carlo\"), or use subset simulation (ensemble.method = \"subset\")",
                       sampling::to_string(c.ensemble.sampling));
  return campaign::validate_sampling(c);
}

std::unique_ptr<Method> make_fixed_design(const campaign::CampaignContext& ctx, const MethodTable&) {
  if (ctx.options.ensemble.sampling == sampling::SamplingMethod::saltelli) return std::make_unique<Saltelli>(ctx);
  return std::make_unique<FixedDesign>(ctx);
}

FixedDesign::FixedDesign(const campaign::CampaignContext& ctx) : ctx_(ctx), plan_(make_plan(ctx)) {
  const campaign::FailureOptions& f = ctx.options.ensemble.method.as<DesignOptions>().failure;
  if (f.kind != campaign::FailureKind::none) failures_.emplace(f);
}

std::vector<std::string> FixedDesign::observed_outputs() const {
  if (!failures_) return {};
  return {ctx_.options.ensemble.method.as<DesignOptions>().failure.column};
}

Proposal FixedDesign::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 1 && failures_) failures_->add(previous);
  if (round > 0) return {};
  return {ctx_.options.ensemble.n_runs, {}};
}

void FixedDesign::calc_uniforms(const RoundPlan&, std::int64_t run, double* u) const {
  if (ctx_.dims.total > 0) plan_.calc_uniforms(run, u);
}

std::optional<FailureEstimate> FixedDesign::calc_failure_estimate(double confidence) const {
  if (!failures_) return std::nullopt;
  return failures_->calc_binomial_estimate(confidence);
}

void FixedDesign::write_results(const ResultsPlace& place) const {
  if (!failures_) return;
  using namespace io::h5;
  const campaign::FailureOptions& f = ctx_.options.ensemble.method.as<DesignOptions>().failure;
  const std::string unit = campaign::find_run_column_unit(f.column);
  Handle g = create_group(place.group, "failure");
  write_failure_attributes(g.get(), f, "failure_units");
  write_scalar(g.get(), "runs", "1", failures_->runs());
  write_scalar(g.get(), "failures", "1", failures_->failures());
  write_scalar(g.get(), "p", "1", failures_->calc_binomial_estimate(0.95).bounds.p);
  write_scalar(g.get(), "nearest_margin", unit.c_str(), failures_->nearest_margin());
}

std::string FixedDesign::calc_result_text() const {
  if (!failures_) return {};
  const campaign::FailureOptions& f = ctx_.options.ensemble.method.as<DesignOptions>().failure;
  const FailureEstimate e = failures_->calc_binomial_estimate(0.95);
  return fmt::format("[truss-campaign] P({} fails) by Monte Carlo: {} failures in {} runs, p = {:.4g} (95 % "
                     "Clopper-Pearson [{:.4g}, {:.4g}])\n", f.column, e.failures, e.runs, e.bounds.p, e.bounds.lower,
                     e.bounds.upper);
}

const std::vector<std::string>& Saltelli::outputs() {
  static const std::vector<std::string> o = {"peak_drive_force_N",      "peak_drive_torque_Nm", "peak_pin_force_N",
                                             "peak_diagonal_tension_N", "peak_latch_energy_J",  "deploy_time_s"};
  return o;
}

OutputSensitivity Saltelli::calc_sensitivity(const std::string& output, const std::vector<std::int8_t>& status,
                                             const std::vector<double>& y) const {
  const campaign::CampaignOptions& c = ctx_.options;
  const std::int64_t block = campaign::saltelli_block_runs(c);
  const int G = static_cast<int>(c.dispersions.size());
  const std::int64_t n_blocks = static_cast<std::int64_t>(status.size()) / block;
  OutputSensitivity s;
  s.output = output;
  std::vector<double> used;
  for (std::int64_t b = 0; b < n_blocks; ++b) {
    const auto first = static_cast<std::size_t>(b * block), end = static_cast<std::size_t>((b + 1) * block);
    bool usable = true;
    for (std::size_t k = first; k < end && usable; ++k) usable = status[k] == 0 && std::isfinite(y[k]);
    if (!usable) {
      ++s.n_blocks_dropped;
      continue;
    }
    used.insert(used.end(), y.begin() + static_cast<std::ptrdiff_t>(first),
                y.begin() + static_cast<std::ptrdiff_t>(end));
    ++s.n_blocks;
  }
  if (s.n_blocks >= 2) {
    s.indices = sampling::calc_sobol_indices(used, G, c.ensemble.master_seed ^ kBootstrapTag, 1000, 0.95);
    return s;
  }
  s.indices.d = G;
  s.indices.n_base = s.n_blocks;
  s.indices.n_resamples = 1000;
  s.indices.confidence = 0.95;
  for (auto* p : {&s.indices.first_order, &s.indices.total, &s.indices.first_order_lo, &s.indices.first_order_hi,
                  &s.indices.total_lo, &s.indices.total_hi})
    p->assign(static_cast<std::size_t>(G), std::numeric_limits<double>::quiet_NaN());
  return s;
}

void Saltelli::write_results(const ResultsPlace& place) const {
  using namespace io::h5;
  const hid_t file = place.file;
  const std::int64_t n_runs = place.n_runs;
  const std::vector<std::int8_t> status = results::read_status(file, n_runs);
  Handle g = create_group(place.group, "sensitivity");
  std::vector<std::string> factors;
  for (const auto& d : ctx_.options.dispersions) factors.push_back(d.key);
  write_strings(g.get(), "factor", factors);
  for (const std::string& name : outputs()) {
    if (ctx_.record.find_output(name) < 0) continue;
    const OutputSensitivity s = calc_sensitivity(name, status, results::read_f64_column(file, "runs/" + name, n_runs));
    Handle o = create_group(g.get(), s.output);
    const auto G = static_cast<std::size_t>(s.indices.d);
    write_array(o.get(), "first_order", "1", s.indices.first_order.data(), G);
    write_array(o.get(), "first_order_lo", "1", s.indices.first_order_lo.data(), G);
    write_array(o.get(), "first_order_hi", "1", s.indices.first_order_hi.data(), G);
    write_array(o.get(), "total", "1", s.indices.total.data(), G);
    write_array(o.get(), "total_lo", "1", s.indices.total_lo.data(), G);
    write_array(o.get(), "total_hi", "1", s.indices.total_hi.data(), G);
    write_int_attribute(o.get(), "n_blocks", s.n_blocks);
    write_int_attribute(o.get(), "n_blocks_dropped", s.n_blocks_dropped);
    write_int_attribute(o.get(), "n_resamples", s.indices.n_resamples);
    write_double_attribute(o.get(), "confidence", s.indices.confidence);
    write_string_attribute(o.get(), "method",
                           "Saltelli et al. 2010 design with one factor per dispersion; first order: Saltelli 2010 "
                           "estimator; total: Jansen 1999; intervals: percentile bootstrap over blocks");
  }
}

}  // namespace truss::methods
