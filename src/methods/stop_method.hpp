// Sequential stopping (ensemble.method = "stop", or its table [ensemble.stop] alone): a Monte
// Carlo design run in rounds until a statistical target holds or the cap on runs is reached
// (sampling/stopping.hpp's rules). Round 0 runs ensemble.n_runs; after each round the rule is
// decided over every run so far and, unless met or capped, asks for the runs it estimates the
// target needs. Run i's point is the Monte Carlo point i, whatever the rounds: the first n_runs
// runs are those of the one-shot design.
//   percentile_bound: the output's values of the ok runs (the others count as runs without a
//     value); probability targets: the share of runs that are not ok.
// [ensemble.stop]: target ("percentile_bound" of output at level; "probability_half_width" |
// "probability_relative_half_width" of the share of failing runs), width, confidence, max_runs (its
// rows: StopOptions::table()). A run fails when it fails the campaign's [failure] event, if it has
// one (the stop rule then estimates that event's probability: failure_event()), else when it is not
// ok. Its resolved TOML keeps the table under method = "design", the form that selects it.
// The results: /stop (docs/hdf5-schema.md): the rule, and per round its runs, estimate, bound,
// achieved width, state and reason; the last round's state and reason say why it stopped.
#pragma once
#include <optional>

#include "campaign/failure.hpp"
#include "campaign/option_table.hpp"
#include "methods/failure_count.hpp"
#include "methods/method.hpp"
#include "sampling/sampling.hpp"
#include "sampling/stopping.hpp"

namespace truss::methods {

struct StopOptions : campaign::MethodOptionsOf<StopOptions> {
  sampling::StopRule rule;
  std::string output;  // percentile_bound: a float64 column of /runs
  campaign::FailureOptions failure;  // [failure]: the event a probability target counts (none: not ok)
  const campaign::FailureOptions* failure_event() const override { return &failure; }
  bool is_percentile() const { return rule.target == sampling::StopTarget::percentile_bound; }
  // A Monte Carlo design (its points extend run by run), a rule that can be met within max_runs
  // (StopRule::validate), a percentile of a float64 column; a [failure] event with a probability
  // target; then the design's own rules.
  std::string validate(const campaign::CampaignOptions& c) const override;
  std::string to_toml() const override;
  std::int64_t calc_max_runs(const campaign::CampaignOptions&) const override { return rule.max_runs; }
  std::string describe_max_runs(const campaign::CampaignOptions&) const override {
    return "ensemble.stop.max_runs = " + std::to_string(rule.max_runs);
  }
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in);
  static const campaign::OptionTable<StopOptions>& table();
  static campaign::TableDoc table_doc() { return campaign::describe_options(table()); }
};

class StopMethod : public Method {
 public:
  explicit StopMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override;
  bool reads_records() const override { return true; }  // a probability target reads the statuses alone
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(const ResultsPlace& place) const override;
  std::string calc_result_text() const override;
  // With a [failure] event: its probability, the failing runs' share (Clopper-Pearson), and how
  // the rule ended.
  std::optional<FailureEstimate> calc_failure_estimate(double confidence) const override;
  // One decision per finished round, in order.
  const std::vector<sampling::StopDecision>& decisions() const { return decisions_; }

 private:
  const campaign::CampaignContext& ctx_;
  const StopOptions& opt_;
  sampling::SamplePlan plan_;  // Monte Carlo over max_runs runs
  std::vector<double> values_;  // percentile: each run's output, NaN unless ok
  std::int64_t runs_ = 0, failures_ = 0;
  std::optional<FailureCount> event_;  // with a [failure] event: its failing runs
  std::vector<sampling::StopDecision> decisions_;
};

}  // namespace truss::methods
