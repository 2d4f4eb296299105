#include "methods/fixed_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/toml_read.hpp"
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
  if (in.table != nullptr)
    for (const auto& [k, v] : *in.table)
      in.ctx.fail(&v, fmt::format("unknown key '{}{}' (the design's keys are ensemble.n_runs and ensemble.sampling)",
                                  in.prefix, k.str()));
  auto o = std::make_unique<DesignOptions>();
  campaign::detail::parse_sweep_failure(in.ctx, in.root, o->failure);
  return o;
}

std::unique_ptr<Method> make_fixed_design(const campaign::CampaignContext& ctx, const MethodTable&) {
  if (ctx.options.ensemble.sampling == sampling::SamplingMethod::saltelli) return std::make_unique<Saltelli>(ctx);
  return std::make_unique<FixedDesign>(ctx);
}

FixedDesign::FixedDesign(const campaign::CampaignContext& ctx) : ctx_(ctx), plan_(make_plan(ctx)) {}

Proposal FixedDesign::propose(std::int64_t round, const RoundRecords&) {
  if (round > 0) return {};
  return {ctx_.options.ensemble.n_runs, {}};
}

void FixedDesign::calc_uniforms(const RoundPlan&, std::int64_t run, double* u) const {
  if (ctx_.dims.total > 0) plan_.calc_uniforms(run, u);
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

void Saltelli::write_results(hid_t file, std::int64_t n_runs) const {
  using namespace io::h5;
  const std::vector<std::int8_t> status = results::read_status(file, n_runs);
  Handle g = create_group(file, "sensitivity");
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
