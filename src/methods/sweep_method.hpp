// A design sweep as a method of the engine: a composite ([sweep], sweep_options.hpp). At each design
// value k it holds the method of value k's standalone campaign (campaign::calc_campaign_at), made by
// the method table, which estimates the probability of the campaign's [failure] event there
// (Method::calc_failure_estimate); the allowable (sampling/allowable.hpp) is read from the estimates.
// The sweep holds the real inner methods: their proposals, points, records and results are theirs.
//
// Scheduling: round r of the sweep is the union of the next round of every running value's method,
// value by value in order of k. Its state is, per value, k and the inner method's own round plan
// (its round, its first local run, its runs, its state bytes). A value's method sees its own runs
// (local run indices from 0) and rounds, as in the standalone campaign, so its estimate is the
// same bytes in the sweep, alone, on any rank count and after --resume. A run's point is its value's
// method's point and, as the last uniform, the design coordinate (k + 0.5) / n_design_values.
//
// Refinement (sweep.refine = m > 0): the listed values run first. When all are done and their
// allowable is found, the m candidates of the bracket of listed values that holds it
// (campaign/design_axis.hpp) start, in the next round; the allowable is then read from every value
// that ran, in order of value. Which bracket is a function of the listed values' records alone, so
// a resumed or re-ranked sweep refines the same one. Without an allowable (the target outside the
// listed values, no safe side) nothing is refined and the file says why.
//
// The results: /sweep (docs/hdf5-schema.md): per value p, CoV, bounds, runs, status; the allowable
// with its interval and the verdict; under /sweep/inner/<k> each value's method writes its own
// results as its standalone campaign writes them at the file's root.
#pragma once
#include <memory>
#include <mutex>
#include <optional>

#include "io/h5_util.hpp"
#include "methods/method.hpp"
#include "methods/sweep_options.hpp"
#include "sampling/allowable.hpp"

namespace truss::methods {

class MethodTable;

class SweepMethod : public Method {
 public:
  SweepMethod(const campaign::CampaignContext& ctx, const MethodTable& methods);
  std::vector<std::string> observed_outputs() const override { return observed_; }
  bool reads_records() const override { return true; }  // it hands each value's method its records
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(const ResultsPlace& place) const override;
  bool runs_are_draws() const override { return false; }
  std::string calc_result_text() const override;
  std::string calc_not_assessed() const override;  // the verdict's reason when NOT ASSESSED

  // One value's result (after the last propose()).
  struct ValueResult {
    std::size_t index = 0;    // its design value index k (campaign::DesignAxis::find_value)
    bool refinement = false;  // a refinement candidate (k >= n_values)
    double value = 0.0;
    std::uint64_t seed = 0;
    FailureEstimate estimate;  // its method's
  };
  // The values that ran, in ascending order of value.
  std::vector<ValueResult> calc_value_results() const;

 private:
  struct Value {
    std::unique_ptr<campaign::CampaignContext> ctx;  // the value's standalone campaign
    std::unique_ptr<Method> method;                  // its method, made by the table
    std::vector<std::size_t> columns;                // its observed outputs among the sweep's
    std::int64_t round = -1;                         // the last round it proposed
    std::int64_t runs = 0;                           // its runs proposed so far (its local run indices)
    std::vector<std::int64_t> rows;                  // the /runs row of each of its runs
    Proposal next;                                   // its proposal for the round being planned
    bool queued = false;  // it runs (every listed value; one bracket's candidates)
    bool done = false;
  };
  // One value's part of a round: its method's round plan, and its first run in the round.
  struct Slice {
    std::uint32_t value = 0;
    RoundPlan plan;
    std::int64_t offset = 0;
  };
  struct Decoded {
    std::int64_t round = -1;
    std::vector<Slice> slices;
  };
  void hand_records(const RoundRecords& previous);  // round r - 1's records to the values that ran
  void start_queued();                              // the queued values' first proposals
  Proposal gather();                                // this round's slices, in order of k
  void queue_refinement();
  std::vector<std::size_t> find_run_order() const;  // the queued values' k, ascending in value
  std::shared_ptr<const Decoded> decode(const RoundPlan& plan) const;

  const campaign::CampaignContext& ctx_;
  const SweepOptions& opt_;
  int dims_ = 0;  // the dispersions' dimensions (the design coordinate is u[dims_])
  std::vector<std::string> observed_;
  std::vector<Value> values_;
  std::vector<Slice> last_;     // the slices of the round proposed last
  bool refined_ = false;        // the refinement's candidates are queued (or it was decided against)
  std::string refine_message_;  // what the refinement did, or why it did not run
  double refine_low_ = std::numeric_limits<double>::quiet_NaN(), refine_high_ = refine_low_;  // its bracket
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const Decoded> decoded_;
};

// The allowable of a sweep's values and the verdict on the campaign's own value, decided together,
// here alone: NOT ASSESSED when a value's estimate is untrusted (FailureEstimate::untrusted: it is
// not read, so it never feeds an allowable) or the values give no allowable; else PASS when the own
// value is on the allowable's safe side, FAIL when not. The file's /sweep/allowable (verdict,
// reason), the terminal and the exit code say what this says; the report displays it.
struct SweepVerdict {
  sampling::Allowable allowable;
  double own_value = 0.0;  // the design variable in the campaign as written
  std::string verdict;     // PASS, FAIL or NOT ASSESSED
  std::string reason;      // one sentence: why
};
SweepVerdict calc_sweep_verdict(const campaign::CampaignOptions& c, const SweepOptions& opt,
                                const std::vector<SweepMethod::ValueResult>& values);

// /sweep under `parent`: the axis' attributes, one row per value and the allowable with the verdict
// (the group, for a method's own additions); and the terminal's lines of the same.
io::h5::Handle write_sweep_group(hid_t parent, const campaign::CampaignOptions& c, const SweepOptions& opt,
                                 const std::vector<SweepMethod::ValueResult>& values);
std::string calc_sweep_text(const campaign::CampaignOptions& c, const SweepOptions& opt,
                            const std::vector<SweepMethod::ValueResult>& values, const std::string& refine_message);

}  // namespace truss::methods
