// [failure] of a campaign file: the failure event whose probability a method estimates (subset
// simulation; a design sweep's inner method at each of its values). A float64 column of /runs and
// its margin, in the column's unit, positive when safe: margin = "<column>": the column itself;
// column = "<column>" with above = threshold: threshold - value; with below = threshold: value -
// threshold; unit = the column's unit. The method whose row reads [failure] holds these options
// (MethodOptions::failure()).
#pragma once
#include <string>

namespace truss::campaign {

enum class FailureKind { none, margin, above, below };
struct FailureOptions {
  FailureKind kind = FailureKind::none;
  std::string column;
  double threshold = 0.0;
  std::string unit;   // above / below: must be the column's unit
  int line = 0;       // of the [failure] table, for messages
};

// The column's rules once a [failure] is given: "" or "failure.<field>: reason".
std::string validate_failure_column(const FailureOptions& f);
// [failure] as resolved TOML ("" for none).
std::string failure_toml(const FailureOptions& f);
// Its parser, detail::parse_failure_table, is declared with the TOML getters (toml_read.hpp).

}  // namespace truss::campaign
