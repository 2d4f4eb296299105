// A design sweep's options ([sweep]): a composite row of the method table (method_options.hpp),
// chosen by its table, that runs the method ensemble.method names at each value of its design axis
// (campaign/design_axis.hpp) and reads the allowable from their estimates (sweep_method.hpp).
//
//   [sweep]
//   key = "drive.stall_torque_Nm"     # a real scene key: its nominal value takes each value
//   spread = "mast.diagonal_free_length_m"  # or, instead of key: the spread of the [[dispersion]]
//                                     # of that key (normal and truncated normal: std; lognormal:
//                                     # sigma; uniform: the half-width about the centre of lower, upper)
//   values = [0.012, 0.015, 0.018]    # strictly ascending, at least 2; or
//   from = 0.012, to = 0.020, count = 5   # evenly spaced, from < to
//   target_probability = 1e-6         # in (0, 1)
//   confidence = 0.95                 # of the one-sided upper bound on p (default 0.95)
//   safe_side = "above"               # where p falls: "above" (larger values are safer: the
//                                     # allowable is a least value) or "below"; a key sweep must
//                                     # declare it; a spread sweep's is "below" (less scatter)
//   refine = 3                        # after the values: this many more, evenly inside the bracket
//                                     # of the allowable (default 0: none)
//
// "Can be swept" is "has a failure event": the inner method's options give one (failure_event(),
// a [failure] table), and its method estimates that event's probability at each value
// (Method::calc_failure_estimate).
#pragma once
#include <limits>
#include <memory>
#include <string>

#include "campaign/design_axis.hpp"
#include "campaign/method_input.hpp"
#include "campaign/option_table.hpp"

namespace truss::methods {

struct SweepOptions : campaign::MethodOptionsOf<SweepOptions> {
  campaign::MethodChoice inner;  // the method run at each value, as a campaign without [sweep] reads it
  campaign::DesignAxis axis;
  double target_probability = 0.0;  // the allowable keeps the upper bound on p at or below this
  double confidence = 0.95;         // of that one-sided upper bound
  int declared_side = 0;            // safe_side: +1 above, -1 below, 0 not given
  // from, to and count as the file gives them (values = evenly spaced; the resolved TOML lists values).
  struct Grid {
    double from = std::numeric_limits<double>::quiet_NaN(), to = std::numeric_limits<double>::quiet_NaN();
    std::int64_t count = 0;
  } grid;

  // Its keys' ranges; a method with a [failure] event at each value and a dispersion to draw; the
  // inner method's own rules on the campaign at the first value (the axis is checked by the campaign).
  std::string validate(const campaign::CampaignOptions& c) const override;
  // Where p falls, never read from the estimates: the declared side, else "below" for a spread
  // (less scatter is safer); a key sweep without safe_side is refused when the file is read.
  int calc_safe_side() const;
  std::string to_toml() const override;  // the inner method's tables, then [sweep]
  std::string chosen_runs() const override { return inner.options().chosen_runs(); }
  std::int64_t calc_n_runs(const campaign::CampaignOptions& c) const override { return inner.options().calc_n_runs(c); }
  // The inner method's at each value the sweep can run (the listed ones and one bracket's candidates);
  // a reweighted sweep's (importance_sweep.hpp) its one set of runs.
  std::int64_t calc_max_runs(const campaign::CampaignOptions& c) const override;
  std::string describe_max_runs(const campaign::CampaignOptions& c) const override;
  const campaign::FailureOptions* failure_event() const override { return inner.options().failure_event(); }
  const campaign::MethodChoice* inner_method() const override { return &inner; }
  const campaign::DesignAxis* design_axis() const override { return &axis; }

  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in);
  static const campaign::OptionTable<SweepOptions>& table();
  static campaign::TableDoc table_doc() { return campaign::describe_options(table()); }
};

}  // namespace truss::methods
