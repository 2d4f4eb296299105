// Subset simulation as a method of the engine (ensemble.method = "subset"): a failure probability
// p = P(margin <= 0) by Au & Beck's subset simulation (sampling/subset_simulation.hpp), each round
// of the state machine one round of the engine. The failure's margin is a float64 column of the
// run record ([failure] of the campaign file): the column itself (margin = ...), or
// its distance to a threshold in the column's unit (above: threshold - value, below: value -
// threshold). A run's margin counts when the run is ok, or when it is <= 0 whatever the status
// (the failure was seen before the run stopped: a rail miss, a peak past its allowable); any
// other run (a stall, a wall-time cap with a positive margin so far) cannot say and counts as safe
// (NaN, SubsetLevel::unusable).
//
// A round's state is SubsetRound::encode() (the level, step, threshold and candidate points), so
// any rank computes any point from the plan alone; the run index is the evaluation ordinal. The
// results: /subset (docs/hdf5-schema.md): p, its CoVs, beta, the levels, the failure samples.
// [ensemble.subset]: SubsetMethodOptions::table().
#pragma once
#include <memory>
#include <mutex>
#include <optional>

#include "campaign/failure.hpp"
#include "campaign/option_table.hpp"
#include "methods/failure_count.hpp"
#include "methods/method.hpp"
#include "sampling/subset_simulation.hpp"

namespace truss::methods {

// Why a subset simulation's estimate cannot feed an allowable, or empty: too many unusable runs
// (find_unusable_reason), or sampling::find_untrusted_reason (no progress, no estimate, a plateau of
// the margin).
std::string find_subset_distrust(const sampling::SubsetSummary& s, std::int64_t unusable, std::int64_t runs);

// [ensemble.subset]: the settings of subset simulation a campaign file gives (sampling::SubsetOptions
// has their rules; its dims and seed come from the dispersions and ensemble.master_seed).
struct SubsetSettings {
  std::int64_t n_per_level = 2000;
  double p0 = 0.1;
  int max_levels = 20;
  // Adaptive conditional sampling with the blended interval CoV: on the shipped rare campaigns their
  // 95 % intervals are 2-3 times narrower at the same runs (docs/benchmarks.md).
  sampling::SubsetProposal proposal = sampling::SubsetProposal::adaptive_conditional;
  double proposal_half_width = 1.0;  // modified Metropolis only
  sampling::SubsetIntervalCov interval_cov = sampling::SubsetIntervalCov::cov_interval;
};

// [failure]: the failure event (campaign/failure.hpp).
using campaign::FailureKind;
using campaign::FailureOptions;

// The subset method's options: it chooses its runs, the cap N + (max_levels - 1)(N - N_c) is the
// campaign's n_runs (an n_runs in the file is refused), and it draws its own points (no sampling).
struct SubsetMethodOptions : campaign::MethodOptionsOf<SubsetMethodOptions> {
  SubsetSettings subset;
  FailureOptions failure;
  std::string validate(const campaign::CampaignOptions& c) const override;
  std::string to_toml() const override;
  std::string chosen_runs() const override {
    return "[ensemble.subset] n_per_level, p0 and max_levels cap them";
  }
  std::int64_t calc_n_runs(const campaign::CampaignOptions& c) const override;
  std::string describe_max_runs(const campaign::CampaignOptions& c) const override;
  const FailureOptions* failure_event() const override { return &failure; }
  // The state machine's options (its dimensions and master seed from the campaign c): the one
  // place the run counts come from (SubsetOptions::max_evaluations).
  sampling::SubsetOptions calc_sim_options(const campaign::CampaignOptions& c) const;
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in);
  static const campaign::OptionTable<SubsetMethodOptions>& table();
  static campaign::TableDoc table_doc() { return campaign::describe_options(table()); }
};

class SubsetMethod : public Method {
 public:
  explicit SubsetMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override { return {opt_.failure.column}; }
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(const ResultsPlace& place) const override;
  // p with its lognormal bounds from the CoV [ensemble.subset] interval_cov names (docs/campaigns.md
  // "Which CoV to read").
  std::optional<FailureEstimate> calc_failure_estimate(double confidence) const override;
  bool runs_are_draws() const override { return false; }
  std::string calc_result_text() const override;  // p, its CoVs, beta, the levels' thresholds
  std::string progress_stage() const override;    // the level, its margin threshold, the Markov step
  std::int64_t run_cap() const override { return ctx_.options.ensemble.n_runs; }  // N + (max_levels - 1)(N - N_c)
  std::string calc_result_failure() const override;  // chains that never moved: no estimate

  // The state machine (after the last propose(): done, with its summary).
  const sampling::SubsetSimulation& simulation() const { return *sim_; }

 private:
  // /subset/failure_samples: run index, margin, z and the inputs of the last level's failing points.
  void write_failure_samples(hid_t group, const ResultsPlace& place, const std::string& unit) const;
  const campaign::CampaignContext& ctx_;
  const SubsetMethodOptions& opt_;
  sampling::SubsetOptions sim_opt_;
  std::optional<sampling::SubsetSimulation> sim_;
  FailureCount margins_;  // the runs' margins as they come
  // The round whose points were asked last, decoded once (every run of a round needs it).
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const sampling::SubsetRound> decoded_;
};

}  // namespace truss::methods
