// A design sweep as a method of the engine ([sweep], campaign/sweep.hpp): at each design value an
// inner method estimates the probability of the campaign's [failure] event, and the allowable
// (sampling/allowable.hpp) is read from the estimates.
//
// Inner method, as the rest of the campaign file says:
//   ensemble.method = "subset"  subset simulation ([ensemble.subset], SubsetMethodOptions), p and its
//                               lineage CoV.
//   [ensemble.stop]             Monte Carlo in rounds until the stop rule's probability target
//                               (StopOptions) holds for the share of failing runs, or max_runs.
//   "design"                    Monte Carlo, n_runs runs (one round).
// The method's options (ensemble.method) hold the [failure] event (MethodOptions::failure_event()).
// The method table makes a SweepMethod for every campaign with a [sweep] (method_table.cpp).
// A run fails when its margin ([failure], SubsetMethod::calc_margins) is <= 0; a run that cannot
// say (NaN margin) counts as safe, as in subset simulation. The smallest margin of each value's runs
// (its nearest approach to failure) tells the allowable the safe side where the estimates cannot
// (p = 0 at both ends: sampling/allowable.hpp).
//
// Scheduling: round r of the sweep is the union of the next round of every running value's inner
// method that is not done, value by value in order of k; the state is, per value, (design value
// index k, its first local run, its runs, its inner state bytes). Value k's inner method is the one
// of the standalone campaign calc_campaign_at(c, k) (its own seed): its run ordinals (local runs)
// and its points are that campaign's, so its estimate is the same bytes in the sweep, alone, on any
// rank count and after --resume. The point's last uniform is the design coordinate
// (k + 0.5) / n_design_values.
//
// Refinement (sweep.refine = m > 0): the listed values run first. When all are done and their
// allowable is found, the m candidates of the bracket of listed values that holds it
// (campaign/sweep.hpp) start, in the next round; the allowable is then read from every value that
// ran, in order of value. Which bracket is a function of the listed values' records alone, so a
// resumed or re-ranked sweep refines the same one. Without an allowable (the target outside the
// listed values, no safe side) nothing is refined and the file says why.
//
// The results: /sweep (docs/hdf5-schema.md): per value p, CoV, bounds, runs, status; the
// allowable with its interval; each value's inner results under /sweep/inner/<k>.
#pragma once
#include <memory>
#include <mutex>
#include <optional>

#include "campaign/failure.hpp"
#include "methods/method.hpp"
#include "sampling/allowable.hpp"
#include "sampling/sampling.hpp"
#include "sampling/stopping.hpp"
#include "sampling/subset_simulation.hpp"

namespace truss::methods {

class SweepMethod : public Method {
 public:
  enum class Inner { subset, monte_carlo, stop };
  explicit SweepMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override { return {failure_.column}; }
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(hid_t file, std::int64_t n_runs) const override;
  bool runs_are_draws() const override { return false; }
  std::string calc_result_text() const override;

  // One value's result (after the last propose()).
  struct ValueResult {
    std::size_t index = 0;    // its design value index k (campaign::SweepOptions::find_value)
    bool refinement = false;  // a refinement candidate (k >= n_values)
    double value = 0.0;
    std::uint64_t seed = 0;
    sampling::ProbabilityBounds bounds;
    double cov = std::numeric_limits<double>::quiet_NaN();
    std::int64_t runs = 0, failures = -1;  // failures: Monte Carlo's count (-1 for subset)
    std::string status, message;
  };
  // The values that ran, in ascending order of value.
  std::vector<ValueResult> calc_value_results() const;
  sampling::Allowable calc_allowable() const;
  Inner inner() const { return inner_; }

 private:
  struct Value {
    std::uint64_t seed = 0;
    sampling::SubsetOptions subset;
    std::optional<sampling::SubsetSimulation> sim;
    std::optional<sampling::SamplePlan> plan;  // Monte Carlo, over the most runs the value can make
    std::int64_t runs = 0, failures = 0;
    double nearest_margin = std::numeric_limits<double>::quiet_NaN();  // the smallest finite margin of its runs
    std::vector<sampling::StopDecision> decisions;
    bool queued = false;   // it runs (every listed value; one bracket's candidates)
    bool started = false;  // its inner method has proposed its first round
    bool done = false;
  };
  // One value's part of a round, as its state holds it.
  struct Slice {
    std::uint32_t value = 0;
    std::int64_t local_first = 0, n_runs = 0, offset = 0;  // offset: its first run in the round
    std::string state;
    std::shared_ptr<const sampling::SubsetRound> round;  // subset: the decoded state
  };
  struct Decoded {
    std::int64_t round = -1;
    std::vector<Slice> slices;
  };
  Proposal propose_value(std::size_t k, Slice& slice);
  Proposal propose_queued();
  void queue_refinement();
  std::vector<std::size_t> find_run_order() const;  // the queued values' k, ascending in value
  void take_records(std::size_t k, const RoundRecords& r);
  std::shared_ptr<const Decoded> decode(const RoundPlan& plan) const;
  void write_inner(hid_t group, std::size_t k) const;

  const campaign::CampaignContext& ctx_;
  Inner inner_;
  const campaign::FailureOptions& failure_;  // the method options' [failure]
  int dims_ = 0;  // the dispersions' dimensions (the design coordinate is u[dims_])
  std::vector<Value> values_;
  std::vector<Slice> last_;  // the slices of the round proposed last
  bool refined_ = false;     // the refinement's candidates are queued (or it was decided against)
  std::string refine_message_;  // what the refinement did, or why it did not run
  double refine_low_ = std::numeric_limits<double>::quiet_NaN(), refine_high_ = refine_low_;  // its bracket
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const Decoded> decoded_;
};

}  // namespace truss::methods
