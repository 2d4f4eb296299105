// Subset simulation as a method of the engine (ensemble.method = "subset"): a failure probability
// p = P(margin <= 0) by Au & Beck's subset simulation (sampling/subset_simulation.hpp), each round
// of the state machine one round of the engine. The failure's margin is a float64 column of the
// run record ([failure] of the campaign file, campaign.hpp): the column itself (margin = ...), or
// its distance to a threshold in the column's unit (above: threshold - value, below: value -
// threshold). A run's margin counts when the run is ok, or when it is <= 0 whatever the status
// (the failure was seen before the run stopped: a rail miss, a peak past its allowable); any
// other run (a stall, a wall-time cap with a positive margin so far) cannot say and counts as safe
// (NaN, SubsetLevel::unusable).
//
// A round's state is SubsetRound::encode() (the level, step, threshold and candidate points), so
// any rank computes any point from the plan alone; the run index is the evaluation ordinal. The
// results: /subset (docs/hdf5-schema.md): p, its CoVs, beta, the levels, the failure samples.
#pragma once
#include <memory>
#include <mutex>
#include <optional>

#include "methods/method.hpp"
#include "sampling/subset_simulation.hpp"

namespace truss::methods {

class SubsetMethod : public Method {
 public:
  explicit SubsetMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override { return {ctx_.options.failure.column}; }
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(hid_t file, std::int64_t n_runs) const override;
  bool runs_are_draws() const override { return false; }
  std::string calc_result_text() const override;  // p, its CoVs, beta, the levels' thresholds
  std::string calc_result_failure() const override;  // chains that never moved: no estimate

  // The margins of a round's records (see above).
  static std::vector<double> calc_margins(const campaign::FailureOptions& f, const RoundRecords& r);
  // The state machine (after the last propose(): done, with its summary).
  const sampling::SubsetSimulation& simulation() const { return *sim_; }

 private:
  // /subset/failure_samples: run index, margin, z and the inputs of the last level's failing points.
  void write_failure_samples(hid_t group, hid_t file, std::int64_t n_runs, const std::string& unit) const;
  const campaign::CampaignContext& ctx_;
  sampling::SubsetOptions opt_;
  std::optional<sampling::SubsetSimulation> sim_;
  // The round whose points were asked last, decoded once (every run of a round needs it).
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const sampling::SubsetRound> decoded_;
};

}  // namespace truss::methods
