// A method's runs against its failure event ([failure], campaign/failure.hpp): each round's
// margins, the runs, the failing runs and the nearest approach to failure. A run's margin counts
// when the run is ok, or when it is <= 0 whatever the status (the failure was seen before the run
// stopped: a rail miss, a peak past its allowable); any other run (a stall, a wall-time cap with a
// positive margin so far) cannot say: its margin is NaN, it is counted as unusable and never as
// safe. More than kMaxUnusableShare of the runs unusable and the estimate is untrusted.
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "campaign/failure.hpp"
#include "methods/method.hpp"

namespace truss::methods {

// The share of an estimate's runs that may lack a usable result before the estimate is untrusted:
// an unusable run may hide a failure, so past this share p may lie well below the true p.
inline constexpr double kMaxUnusableShare = 0.01;

// Why an estimate from `runs` runs, `unusable` of them without a usable result, cannot be trusted
// (more than kMaxUnusableShare of them unusable), or empty.
std::string find_unusable_reason(std::int64_t unusable, std::int64_t runs);

class FailureCount {
 public:
  explicit FailureCount(const campaign::FailureOptions& f) : f_(f) {}
  // The margins of a round's records, outputs[column] the event's column, counted.
  std::vector<double> add(const RoundRecords& r, std::size_t column = 0);
  std::int64_t runs() const { return runs_; }
  std::int64_t failures() const { return failures_; }
  std::int64_t unusable() const { return unusable_; }  // runs whose margin is NaN
  // The smallest finite margin of the runs (NaN: none yet): how near the runs came to failure.
  double nearest_margin() const { return nearest_; }
  // p = failures / n, n the usable runs, with its Clopper-Pearson bounds and CoV sqrt((1 - p) / (n p))
  // (NaN at p = 0); runs: every run; status "done" ("not_run" without runs), message "k failures in n
  // usable runs (u unusable)"; untrusted by find_unusable_reason.
  FailureEstimate calc_binomial_estimate(double confidence) const;
  // The margins alone (see above).
  static std::vector<double> calc_margins(const campaign::FailureOptions& f, const RoundRecords& r,
                                          std::size_t column = 0);

 private:
  const campaign::FailureOptions& f_;
  std::int64_t runs_ = 0, failures_ = 0, unusable_ = 0;
  double nearest_ = std::numeric_limits<double>::quiet_NaN();
};

// The event as the results file's groups describe it: attributes failure_column, failure_kind
// (margin, above, below), failure_threshold (0 for a margin) and the column's unit as `units_name`.
void write_failure_attributes(hid_t obj, const campaign::FailureOptions& f, const char* units_name);

}  // namespace truss::methods
