// Cross-entropy importance sampling as a method of the engine (ensemble.method = "importance"): a
// failure probability p = P(margin <= 0) from runs drawn from a density adapted to the failure
// region (sampling/importance_sampling.hpp), each round of the state machine one round of the
// engine: its cross-entropy levels, then the final round whose weighted runs the estimate rests on
// (sampling/reweighting.hpp: p, its CoV, the lognormal interval, the effective sample size, the
// Pareto k, refused with its reason where the weights degenerate). The margin is the [failure]
// event's, as the subset method reads it (failure_count.hpp: NaN for a run that cannot say).
//
// A round's state is ImportanceRound::encode() (its density's mean): any rank computes any point
// from the plan alone, the run index being the evaluation ordinal. The adaptation reads the margins
// in run-index order (the engine's records), never in arrival order.
//
// A composite that reweights the runs to other laws (importance_sweep.hpp) gives the density a
// target to adapt to (set_adaptation_ratio: ln f / phi of a run's point, the mixture of its laws),
// may draw the final runs from another deviation density (set_final_deviation: the mixture of a
// spread sweep's laws, sampling/law_mixture.hpp) and reads the final runs (sampler()). The
// results: /importance (docs/hdf5-schema.md).
// [ensemble.importance]: ImportanceMethodOptions::table().
#pragma once
#include <functional>
#include <memory>
#include <mutex>
#include <optional>

#include "campaign/failure.hpp"
#include "campaign/option_table.hpp"
#include "methods/failure_count.hpp"
#include "methods/method.hpp"
#include "sampling/importance_sampling.hpp"
#include "sampling/reweighting.hpp"

namespace truss::methods {

// [ensemble.importance]: sampling::ImportanceOptions has their rules (its dims and seed come from
// the dispersions and ensemble.master_seed).
struct ImportanceSettings {
  std::int64_t n_per_level = 1000;
  std::int64_t n_final = 2000;
  double rho = 0.1;
  int max_levels = 20;
};

// The confidence of the interval the method writes and prints (a sweep's inner estimates use the
// sweep's own).
inline constexpr double kImportanceConfidence = 0.95;

struct ImportanceMethodOptions : campaign::MethodOptionsOf<ImportanceMethodOptions> {
  ImportanceSettings importance;
  campaign::FailureOptions failure;
  std::string validate(const campaign::CampaignOptions& c) const override;
  std::string to_toml() const override;
  std::string chosen_runs() const override {
    return "[ensemble.importance] n_per_level, max_levels and n_final cap them";
  }
  std::int64_t calc_n_runs(const campaign::CampaignOptions& c) const override;
  std::string describe_max_runs(const campaign::CampaignOptions& c) const override;
  const campaign::FailureOptions* failure_event() const override { return &failure; }
  // The state machine's options (dimensions and seed from the campaign c): the one place the run
  // counts come from (ImportanceOptions::max_evaluations).
  sampling::ImportanceOptions calc_sim_options(const campaign::CampaignOptions& c) const;
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in);
  static const campaign::OptionTable<ImportanceMethodOptions>& table();
  static campaign::TableDoc table_doc() { return campaign::describe_options(table()); }
};

class ImportanceMethod : public Method {
 public:
  explicit ImportanceMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override { return {opt_.failure.column}; }
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(const ResultsPlace& place) const override;
  std::optional<FailureEstimate> calc_failure_estimate(double confidence) const override;
  bool runs_are_draws() const override { return false; }  // draws of the adapted density, not the law
  std::string calc_result_text() const override;
  std::string progress_stage() const override;
  std::int64_t run_cap() const override { return ctx_.options.ensemble.n_runs; }
  std::string calc_result_failure() const override;  // a refused estimate: no result

  // ln f / phi of a point (its campaign uniforms) for the density to adapt to (see above); before
  // the first propose().
  void set_adaptation_ratio(std::function<double(const double* u)> ratio) { ratio_ = std::move(ratio); }
  // The final round's deviation density (nullptr: N(0, I)); it must outlive the method.
  void set_final_deviation(const sampling::Deviation* g) { deviation_ = g; }
  const sampling::CrossEntropySampler& sampler() const { return *sim_; }
  std::int64_t unusable() const { return margins_.unusable(); }
  // The estimate under the campaign's own law (the final runs' weights), refused with the
  // sampler's reason, or with too many unusable runs, too.
  sampling::WeightedEstimate calc_estimate(double confidence) const;

 private:
  std::vector<double> calc_round_ratios(const sampling::ImportanceRound& r) const;
  const campaign::CampaignContext& ctx_;
  const ImportanceMethodOptions& opt_;
  sampling::ImportanceOptions sim_opt_;
  std::optional<sampling::CrossEntropySampler> sim_;
  FailureCount margins_;
  std::function<double(const double* u)> ratio_;
  const sampling::Deviation* deviation_ = nullptr;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const sampling::ImportanceRound> decoded_;
};

// A weighted estimate as a method's FailureEstimate (failures -1: p is not a count); untrusted
// when refused (its reason) or past the unusable share.
FailureEstimate to_failure_estimate(const sampling::WeightedEstimate& w, const sampling::CrossEntropySampler& s,
                                    std::int64_t runs, std::int64_t unusable);

// /importance's datasets of an estimate (p, cov, lower, upper, upper_bound, ess, pareto_k, counts)
// and the adaptation's levels, as the standalone method and the reweighted sweep write them.
void write_weighted_estimate(hid_t g, const sampling::WeightedEstimate& w);
void write_adaptation(hid_t g, const sampling::CrossEntropySampler& s, const campaign::FailureOptions& f);

}  // namespace truss::methods
