#include "methods/importance_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"

namespace truss::methods {

namespace {

// The one dispersion of the swept key (-1: none or several), and the field the message names.
int find_swept_dispersion(const campaign::CampaignOptions& c, const campaign::DesignAxis& a, std::string& why) {
  int found = -1;
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
    if (c.dispersions[i].key != a.key) continue;
    if (found >= 0) {
      why = fmt::format("\"{}\" is dispersed twice: which draw the values change is ambiguous", a.key);
      return -1;
    }
    found = static_cast<int>(i);
  }
  if (found < 0)
    why = fmt::format("\"{}\" is not dispersed: its value changes the model, not a distribution, so the runs of one "
                      "value cannot serve another; use ensemble.method = \"subset\"", a.key);
  return found;
}

// Value k's law of the draws, in the base's coordinate (reweighting.hpp: DrawLaw).
sampling::DrawLaw make_value_law(const campaign::CampaignOptions& c, const SweepOptions& opt, std::size_t i,
                                 std::size_t k, std::size_t base) {
  const campaign::DispersionOptions& d = c.dispersions[i];
  if (opt.axis.variable == campaign::SweepVariable::spread) {
    campaign::CampaignOptions at = c;
    campaign::apply_design_value(c, k, at);
    return {campaign::make_distribution(at.dispersions[i]), 1.0, 0.0};
  }
  const double nk = opt.axis.find_value(k), nb = opt.axis.find_value(base);
  const sampling::Distribution dist = campaign::make_distribution(d);
  if (d.apply == campaign::Apply::offset) return {dist, 1.0, nk - nb};
  return {dist, nk / nb, nk / nb - 1.0};  // relative: n (1 + d)
}

}  // namespace

std::string find_sweep_laws(const campaign::CampaignOptions& c, const SweepOptions& opt, SweepLaws& laws) {
  const campaign::DesignAxis& a = opt.axis;
  const bool spread = a.variable == campaign::SweepVariable::spread;
  const std::string field = spread ? "sweep.spread: " : "sweep.key: ";
  if (a.refine > 0)
    return "sweep.refine: the reweighted sweep (ensemble.method = \"importance\") estimates every listed value from "
           "the same runs: list the values wanted instead of refining";
  std::string why;
  const int i = find_swept_dispersion(c, a, why);
  if (i < 0) return field + why;
  const auto di = static_cast<std::size_t>(i);
  if (!spread && c.dispersions[di].apply == campaign::Apply::absolute)
    return field +
           fmt::format("\"{}\" is dispersed with apply = \"absolute\": its nominal value changes nothing", a.key);
  if (!spread && c.dispersions[di].apply == campaign::Apply::relative)
    for (double v : a.values)
      if (!(v > 0.0))
        return field + fmt::format("a relative draw of \"{}\" needs nominal values above 0, got {}", a.key, v);
  // The base: the widest spread (the last value), or the middle nominal.
  laws.base = spread ? a.n_values() - 1 : a.n_values() / 2;
  laws.spread = spread;
  const campaign::DimensionLayout L = campaign::calc_layout(campaign::calc_campaign_at(c, laws.base));
  sampling::SweptBlock& b = laws.block;
  b.offset = L.offset[di];
  b.count = L.count[di];
  b.base = {L.distributions[di], 1.0, 0.0};
  b.laws.clear();
  for (std::size_t k = 0; k < a.n_values(); ++k) {
    b.laws.push_back(make_value_law(c, opt, di, k, laws.base));
    if (const std::string r = sampling::find_reweighting_refusal(b.base, b.laws.back()); !r.empty())
      return field + fmt::format("the runs at {:.6g} cannot be reweighted to {:.6g}: {}", a.values[laws.base],
                                 a.values[k], r);
  }
  return {};
}

std::string validate_reweighted_sweep(const campaign::CampaignOptions& c, const SweepOptions& opt) {
  SweepLaws laws;
  return find_sweep_laws(c, opt, laws);
}

ImportanceSweepMethod::ImportanceSweepMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx), opt_(ctx.options.ensemble.method.as<SweepOptions>()), dims_(ctx.dims.dispersion_dims()) {
  if (const std::string why = find_sweep_laws(ctx.options, opt_, laws_); !why.empty())
    throw std::logic_error("importance sweep: " + why);
  base_ctx_ = std::make_unique<campaign::CampaignContext>(campaign::calc_campaign_at(ctx.options, laws_.base));
  method_ = std::make_unique<ImportanceMethod>(*base_ctx_);
  // The density adapts to the mixture of the values' laws: ln (1/K) sum_k f_k / f_b.
  method_->set_adaptation_ratio([this](const double* u) { return laws_.block.calc_log_mixture_ratio(u); });
  // A spread sweep's final runs: the same laws, carried to the adapted mean (law_mixture.hpp).
  if (laws_.spread) {
    mixture_ = std::make_unique<sampling::LawMixture>(laws_.block, dims_);
    method_->set_final_deviation(mixture_.get());
  }
}

void ImportanceSweepMethod::calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const {
  method_->calc_uniforms(plan, run, u);
  u[dims_] = (static_cast<double>(laws_.base) + 0.5) / static_cast<double>(opt_.axis.n_design_values());
}

std::vector<sampling::WeightedEstimate> ImportanceSweepMethod::calc_weighted_estimates() const {
  const sampling::CrossEntropySampler& s = method_->sampler();
  std::vector<sampling::WeightedEstimate> out(laws_.block.laws.size());
  if (!s.done()) return out;
  const std::vector<double> base_w = s.calc_final_log_weights(mixture_.get());
  const sampling::ImportanceOptions& o = s.options();
  std::vector<std::vector<double>> log_w(out.size(), base_w);
  std::vector<double> u(static_cast<std::size_t>(o.dims)), r(out.size());
  for (std::size_t i = 0; i < base_w.size(); ++i) {
    sampling::calc_round_uniforms(o, s.final_round(), static_cast<std::int64_t>(i), u.data(), mixture_.get());
    laws_.block.calc_log_ratios(u.data(), r);
    for (std::size_t k = 0; k < out.size(); ++k) log_w[k][i] += r[k];
  }
  const std::string density = s.find_refusal();
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = sampling::calc_weighted_estimate(s.final_margins(), log_w[k], opt_.confidence);
    if (out[k].refused.empty()) out[k].refused = density;
    if (!out[k].refused.empty()) out[k].bounds = {};
  }
  return out;
}

std::vector<SweepMethod::ValueResult> ImportanceSweepMethod::calc_value_results() const {
  const std::vector<sampling::WeightedEstimate> w = calc_weighted_estimates();
  std::vector<SweepMethod::ValueResult> out(w.size());
  const sampling::CrossEntropySampler& s = method_->sampler();
  for (std::size_t k = 0; k < w.size(); ++k) {
    out[k].index = k;
    out[k].value = opt_.axis.values[k];
    out[k].seed = ctx_.options.ensemble.master_seed;
    out[k].estimate = to_failure_estimate(w[k], s, s.runs(), method_->unusable());
  }
  return out;
}

std::string ImportanceSweepMethod::calc_not_assessed() const {
  const SweepVerdict v = calc_sweep_verdict(ctx_.options, opt_, calc_value_results());
  return v.verdict == "NOT ASSESSED" ? v.reason : std::string();
}

std::string ImportanceSweepMethod::calc_result_text() const {
  std::string t = method_->calc_result_text();
  const std::size_t cut = t.find('\n');  // its first line speaks of the base value's law alone
  const std::string levels = cut == std::string::npos ? "" : t.substr(t.find('\n', cut + 1) + 1);
  return calc_sweep_text(ctx_.options, opt_, calc_value_results(), "") + levels;
}

void ImportanceSweepMethod::write_results(const ResultsPlace& place) const {
  const std::vector<SweepMethod::ValueResult> vr = calc_value_results();
  io::h5::Handle g = write_sweep_group(place.group, ctx_.options, opt_, vr);
  io::h5::Handle h = io::h5::create_group(g.get(), "importance");
  write_adaptation(h.get(), method_->sampler(), *opt_.failure_event());
  io::h5::write_int_attribute(h.get(), "base_index", static_cast<std::int64_t>(laws_.base));
  io::h5::write_scalar(h.get(), "unusable", "1", method_->unusable());
  const std::vector<sampling::WeightedEstimate> w = calc_weighted_estimates();
  std::vector<double> ess(w.size()), k(w.size());
  std::vector<std::string> refused(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) {
    ess[i] = w[i].ess;
    k[i] = w[i].pareto_k;
    refused[i] = w[i].refused;
  }
  io::h5::write_array(h.get(), "ess", "1", ess.data(), ess.size());
  io::h5::write_array(h.get(), "pareto_k", "1", k.data(), k.size());
  io::h5::write_strings(h.get(), "refused", refused);
}

}  // namespace truss::methods
