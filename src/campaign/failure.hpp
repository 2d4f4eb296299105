// [failure] of a campaign file: the failure event whose probability a method estimates (subset
// simulation, Monte Carlo, the stop rule's probability targets; a design sweep's inner method at each
// of its values). A float64 column of /runs and its margin, in the column's unit, positive when
// safe: margin = "<column>": the column itself; column = "<column>" with above = threshold:
// threshold - value; with below = threshold: value - threshold; unit = the column's unit. The
// method whose row reads [failure] holds these options (MethodOptions::failure_event()); its rows
// are failure_table(), read by read_failure_event (method_input.hpp).
#pragma once
#include <string>

#include "campaign/option_table.hpp"

namespace truss::campaign {

struct CampaignOptions;

enum class FailureKind { none, margin, above, below };
struct FailureOptions {
  FailureKind kind = FailureKind::none;
  std::string column;
  double threshold = 0.0;
  std::string unit;   // above / below: must be the column's unit
  int line = 0;       // of the [failure] table, for messages
};

const OptionTable<FailureOptions>& failure_table();

// The event's rules over the campaign once a [failure] is given: "" or "failure.<field>: reason":
// a float64 column of /runs, the threshold in its unit, and a column the campaign's scene defines
// (a margin NaN in every run, as motor_torque_margin_Nm under drive.mode = "motor", never fails).
std::string validate_failure_event(const FailureOptions& f, const CampaignOptions& c);
// [failure] as resolved TOML ("" for none).
std::string failure_toml(const FailureOptions& f);
// The margin of a run whose column holds `value`: positive safe, failed at or below 0.
inline double calc_failure_margin(const FailureOptions& f, double value) {
  return f.kind == FailureKind::above   ? f.threshold - value
         : f.kind == FailureKind::below ? value - f.threshold
                                        : value;
}

}  // namespace truss::campaign
