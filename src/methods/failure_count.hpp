// A method's runs against its failure event ([failure], campaign/failure.hpp): each round's
// margins, the runs, the failing runs and the nearest approach to failure. A run's margin counts
// when the run is ok, or when it is <= 0 whatever the status (the failure was seen before the run
// stopped: a rail miss, a peak past its allowable); any other run (a stall, a wall-time cap with a
// positive margin so far) cannot say and counts as safe (NaN).
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "campaign/failure.hpp"
#include "methods/method.hpp"

namespace truss::methods {

class FailureCount {
 public:
  explicit FailureCount(const campaign::FailureOptions& f) : f_(f) {}
  // The margins of a round's records, outputs[column] the event's column, counted.
  std::vector<double> add(const RoundRecords& r, std::size_t column = 0);
  std::int64_t runs() const { return runs_; }
  std::int64_t failures() const { return failures_; }
  // The smallest finite margin of the runs (NaN: none yet): how near the runs came to failure.
  double nearest_margin() const { return nearest_; }
  // p = failures / runs with its Clopper-Pearson bounds and CoV sqrt((1 - p) / (n p)) (NaN at p = 0);
  // status "done" ("not_run" without runs), message "k failures in n runs".
  FailureEstimate calc_binomial_estimate(double confidence) const;
  // The margins alone (see above).
  static std::vector<double> calc_margins(const campaign::FailureOptions& f, const RoundRecords& r,
                                          std::size_t column = 0);

 private:
  const campaign::FailureOptions& f_;
  std::int64_t runs_ = 0, failures_ = 0;
  double nearest_ = std::numeric_limits<double>::quiet_NaN();
};

// The event as the results file's groups describe it: attributes failure_column, failure_kind
// (margin, above, below), failure_threshold (0 for a margin) and the column's unit as `units_name`.
void write_failure_attributes(hid_t obj, const campaign::FailureOptions& f, const char* units_name);

}  // namespace truss::methods
