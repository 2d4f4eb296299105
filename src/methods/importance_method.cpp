#include "methods/importance_method.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"
#include "campaign/method_input.hpp"
#include "io/h5_util.hpp"

namespace truss::methods {

ImportanceMethod::ImportanceMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      opt_(ctx.options.ensemble.method.as<ImportanceMethodOptions>()),
      sim_opt_(opt_.calc_sim_options(ctx.options)),
      margins_(opt_.failure) {
  if (ctx_.record.find_output(opt_.failure.column) < 0)
    throw std::logic_error(fmt::format("importance: {} is not a float64 output of the record", opt_.failure.column));
}

// ln f / phi of each point of round r (the adaptation's target), in the round's order.
std::vector<double> ImportanceMethod::calc_round_ratios(const sampling::ImportanceRound& r) const {
  if (!ratio_) return {};
  std::vector<double> out(static_cast<std::size_t>(r.n_points)), u(static_cast<std::size_t>(sim_opt_.dims));
  for (std::int64_t k = 0; k < r.n_points; ++k) {
    sampling::calc_round_uniforms(sim_opt_, r, k, u.data());
    out[static_cast<std::size_t>(k)] = ratio_(u.data());
  }
  return out;
}

Proposal ImportanceMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) {
    sim_.emplace(sim_opt_);
  } else {
    if (!sim_ || sim_->done()) return {};
    const std::vector<double> m = margins_.add(previous);
    sim_->add_margins(m, sim_->round().final ? std::vector<double>{} : calc_round_ratios(sim_->round()));
    if (sim_->done()) return {};
  }
  const sampling::ImportanceRound& r = sim_->round();
  const std::int64_t first = round == 0 ? 0 : previous.first_run + static_cast<std::int64_t>(previous.status.size());
  if (r.first_evaluation != first)  // the run index is the evaluation ordinal: the points are keyed by it
    throw std::logic_error(fmt::format("importance: round {} starts at evaluation {}, run {}", round,
                                       r.first_evaluation, first));
  return {r.n_points, r.encode()};
}

void ImportanceMethod::calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const {
  std::shared_ptr<const sampling::ImportanceRound> r;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!decoded_ || decoded_->index != plan.round)
      decoded_ = std::make_shared<const sampling::ImportanceRound>(
          sampling::ImportanceRound::decode(plan.state, sim_opt_.dims));
    r = decoded_;
  }
  sampling::calc_round_uniforms(sim_opt_, *r, run - plan.first_run, u, deviation_);
}

sampling::ImportanceOptions ImportanceMethodOptions::calc_sim_options(const campaign::CampaignOptions& c) const {
  sampling::ImportanceOptions o;
  o.dims = campaign::calc_layout(c).dispersion_dims();
  o.n_per_level = importance.n_per_level;
  o.n_final = importance.n_final;
  o.rho = importance.rho;
  o.max_levels = importance.max_levels;
  o.seed = c.ensemble.master_seed;
  return o;
}

std::int64_t ImportanceMethodOptions::calc_n_runs(const campaign::CampaignOptions& c) const {
  const sampling::ImportanceOptions s = calc_sim_options(c);
  return s.validate().empty() ? s.max_evaluations() : 0;
}

std::string ImportanceMethodOptions::describe_max_runs(const campaign::CampaignOptions& c) const {
  return fmt::format("ensemble.importance.n_per_level = {}, max_levels = {}, n_final = {} (at most {} runs)",
                     importance.n_per_level, importance.max_levels, importance.n_final, c.ensemble.n_runs);
}

const campaign::OptionTable<ImportanceMethodOptions>& ImportanceMethodOptions::table() {
  using S = ImportanceMethodOptions;
  static const campaign::OptionTable<S> t{
      "ensemble.importance",
      "cross-entropy importance sampling of the [failure] event's probability: it chooses its runs", {
          TRUSS_OPTION_INT(S, "n_per_level", importance.n_per_level, "1", campaign::kAnyNumber,
                           "runs of each cross-entropy level that adapts the density (rho n_per_level >= 1)"),
          TRUSS_OPTION_INT(S, "n_final", importance.n_final, "1", campaign::kAnyNumber,
                           "runs drawn from the adapted density: the estimate rests on these alone (>= 2)"),
          TRUSS_OPTION_REAL(S, "rho", importance.rho, "1", campaign::kAnyNumber,
                            "elite share of a level: its threshold is this quantile of the margins, in (0, 0.5]"),
          TRUSS_OPTION_INT(S, "max_levels", importance.max_levels, "1", campaign::closed_range(1, 1000),
                           "cross-entropy levels at most: the run cap max_levels n_per_level + n_final"),
      }};
  return t;
}

std::unique_ptr<campaign::MethodOptions> ImportanceMethodOptions::parse(const campaign::MethodInput& in) {
  auto o = std::make_unique<ImportanceMethodOptions>();
  campaign::read_method_table(in, table(), *o);
  campaign::read_failure_event(in, o->failure);
  return o;
}

std::string ImportanceMethodOptions::validate(const campaign::CampaignOptions& o) const {
  if (o.ensemble.sampling != sampling::SamplingMethod::monte_carlo)
    return "ensemble.sampling: method = \"importance\" draws its own points (from its adapted density): remove "
           "sampling";
  if (o.dispersions.empty()) return "ensemble.method: importance sampling needs at least one [[dispersion]]";
  if (const std::string e = calc_sim_options(o).validate(); !e.empty()) return "ensemble.importance." + e;
  if (failure.kind == campaign::FailureKind::none)
    return "failure: method = \"importance\" needs a [failure] table: margin = \"rail_margin_m\", or column = "
           "\"peak_drive_force_N\", above = 3.5, unit = \"N\"";
  return campaign::check_option_ranges(table(), *this, "ensemble.importance.");
}

std::string ImportanceMethodOptions::to_toml() const {
  return "[ensemble.importance]\n" + campaign::write_options(table(), *this) + "\n" + campaign::failure_toml(failure);
}

sampling::WeightedEstimate ImportanceMethod::calc_estimate(double confidence) const {
  if (!sim_ || !sim_->done()) return {};
  sampling::WeightedEstimate w =
      sampling::calc_weighted_estimate(sim_->final_margins(), sim_->calc_final_log_weights(deviation_), confidence);
  if (w.refused.empty()) w.refused = sim_->find_refusal();
  if (!w.refused.empty()) w.bounds = {};
  return w;
}

FailureEstimate to_failure_estimate(const sampling::WeightedEstimate& w, const sampling::CrossEntropySampler& s,
                                    std::int64_t runs, std::int64_t unusable) {
  FailureEstimate e;
  e.bounds = w.bounds;
  e.bounds.p = w.p;
  e.cov = w.cov;
  e.runs = runs;
  e.unusable = unusable;
  e.status = w.refused.empty() ? sampling::to_string(s.status()) : "refused";
  e.message = w.refused.empty()
                  ? fmt::format("{}; {} failing of {} final runs, ESS {:.3g}, Pareto k {:.2f}", s.message(),
                                w.failures, w.runs, w.ess, w.pareto_k)
                  : w.refused;
  e.untrusted = find_unusable_reason(unusable, runs);  // an unusable run may hide a failure: said first
  if (e.untrusted.empty() && !w.refused.empty()) e.untrusted = "refused: " + w.refused;
  return e;
}

std::optional<FailureEstimate> ImportanceMethod::calc_failure_estimate(double confidence) const {
  if (!sim_ || !sim_->done()) return FailureEstimate{};
  FailureEstimate e = to_failure_estimate(calc_estimate(confidence), *sim_, margins_.runs(), margins_.unusable());
  e.nearest_margin = margins_.nearest_margin();
  return e;
}

std::string ImportanceMethod::calc_result_failure() const {
  if (!sim_ || !sim_->done()) return {};
  const sampling::WeightedEstimate w = calc_estimate(kImportanceConfidence);
  return w.refused.empty() ? std::string() : "importance sampling has no estimate: " + w.refused;
}

std::string ImportanceMethod::progress_stage() const {
  if (!sim_ || sim_->done()) return {};
  const sampling::ImportanceRound& r = sim_->round();
  if (r.final) return fmt::format("final runs (after {} cross-entropy levels)", r.level);
  return fmt::format("cross-entropy level {}", r.level);
}

std::string ImportanceMethod::calc_result_text() const {
  if (!sim_ || !sim_->done()) return {};
  const sampling::WeightedEstimate w = calc_estimate(kImportanceConfidence);
  const campaign::FailureOptions& f = opt_.failure;
  const std::string unit = campaign::find_run_column_unit(f.column);
  std::string t = fmt::format("[truss-campaign] importance sampling of P({} {} {} {}): {} ({})\n", f.column,
                              f.kind == campaign::FailureKind::above ? ">=" : "<=",
                              f.kind == campaign::FailureKind::margin ? 0.0 : f.threshold, unit,
                              sampling::to_string(sim_->status()), sim_->message());
  if (w.refused.empty())
    t += fmt::format("[truss-campaign]   p = {:.4g}, CoV {:.3g}, 95 % interval [{:.4g}, {:.4g}]; {} failing of {} "
                     "final runs, ESS {:.3g}, Pareto k {:.2f}; {} runs\n", w.p, w.cov, w.bounds.lower,
                     w.bounds.upper, w.failures, w.runs, w.ess, w.pareto_k, margins_.runs());
  else
    t += fmt::format("[truss-campaign]   no estimate: {}\n", w.refused);
  const auto& lv = sim_->levels();
  for (std::size_t k = 0; k < lv.size(); ++k)
    t += fmt::format("[truss-campaign]   level {}: margin <= {:.6g} {}, {} elites, density shifted {:.3g}\n", k,
                     lv[k].threshold, unit, lv[k].elites, lv[k].shift);
  return t;
}

using namespace io::h5;

void write_weighted_estimate(hid_t g, const sampling::WeightedEstimate& w) {
  write_string_attribute(g, "refused", w.refused);
  write_double_attribute(g, "confidence", kImportanceConfidence);
  write_scalar(g, "p", "1", w.p);
  write_scalar(g, "cov", "1", w.cov);
  write_scalar(g, "lower", "1", w.bounds.lower);
  write_scalar(g, "upper", "1", w.bounds.upper);
  write_scalar(g, "upper_bound", "1", w.bounds.upper_bound);
  write_scalar(g, "ess", "1", w.ess);
  write_scalar(g, "pareto_k", "1", w.pareto_k);
  write_scalar(g, "final_runs", "1", w.runs);
  write_scalar(g, "failures", "1", w.failures);
}

void write_adaptation(hid_t g, const sampling::CrossEntropySampler& s, const campaign::FailureOptions& f) {
  write_string_attribute(g, "status", sampling::to_string(s.status()));
  write_string_attribute(g, "message", s.message());
  write_string_attribute(g, "density_refusal", s.find_refusal());
  write_failure_attributes(g, f, "margin_units");
  const sampling::ImportanceOptions& o = s.options();
  write_int_attribute(g, "n_per_level", o.n_per_level);
  write_int_attribute(g, "n_final", o.n_final);
  write_double_attribute(g, "rho", o.rho);
  write_int_attribute(g, "max_levels", o.max_levels);
  write_scalar(g, "runs", "1", s.runs());
  const std::vector<double>& mean = s.final_round().mean;
  write_array(g, "final_mean", "1", mean.data(), mean.size());
  Handle lv = create_group(g, "levels");
  const auto& L = s.levels();
  const std::size_t n = L.size();
  std::vector<double> threshold(n), ess(n), shift(n), noise(n);
  std::vector<std::int64_t> elites(n), runs(n), unusable(n), moved(n);
  for (std::size_t k = 0; k < n; ++k) {
    threshold[k] = L[k].threshold;
    ess[k] = L[k].elite_ess;
    shift[k] = L[k].shift;
    noise[k] = L[k].mean_noise;
    elites[k] = L[k].elites;
    runs[k] = L[k].runs;
    unusable[k] = L[k].unusable;
    moved[k] = L[k].moved;
  }
  const std::string unit = campaign::find_run_column_unit(f.column);
  write_array(lv.get(), "threshold", unit.c_str(), threshold.data(), n);
  write_array(lv.get(), "elite_ess", "1", ess.data(), n);
  write_array(lv.get(), "shift", "1", shift.data(), n);
  write_array(lv.get(), "mean_noise", "1", noise.data(), n);
  write_array(lv.get(), "elites", "1", elites.data(), n);
  write_array(lv.get(), "runs", "1", runs.data(), n);
  write_array(lv.get(), "unusable", "1", unusable.data(), n);
  write_array(lv.get(), "moved", "1", moved.data(), n);
}

void ImportanceMethod::write_results(const ResultsPlace& place) const {
  if (!sim_ || !sim_->done()) return;
  Handle g = create_group(place.group, "importance");
  write_adaptation(g.get(), *sim_, opt_.failure);
  write_weighted_estimate(g.get(), calc_estimate(kImportanceConfidence));
  write_scalar(g.get(), "unusable", "1", margins_.unusable());
}

}  // namespace truss::methods
