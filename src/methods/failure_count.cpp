#include "methods/failure_count.hpp"

#include <cmath>

#include <fmt/format.h>

#include "io/h5_util.hpp"

namespace truss::methods {

std::string find_unusable_reason(std::int64_t unusable, std::int64_t runs) {
  if (!(static_cast<double>(unusable) > kMaxUnusableShare * static_cast<double>(runs))) return {};
  return fmt::format("{} of {} runs have no usable result (capped by steps or wall time, a solver failure or a NaN "
                     "margin), more than {:g} %",
                     unusable, runs, 100.0 * kMaxUnusableShare);
}

std::vector<double> FailureCount::calc_margins(const campaign::FailureOptions& f, const RoundRecords& r,
                                               std::size_t column) {
  const std::vector<double>& y = r.outputs.at(column);
  std::vector<double> m(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double v = campaign::calc_failure_margin(f, y[i]);
    const bool says = r.status[i] == static_cast<std::int8_t>(sim::RunStatus::ok) || v <= 0.0;
    m[i] = says ? v : std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

std::vector<double> FailureCount::add(const RoundRecords& r, std::size_t column) {
  std::vector<double> m = calc_margins(f_, r, column);
  runs_ += static_cast<std::int64_t>(m.size());
  for (double x : m) {
    failures_ += x <= 0.0 ? 1 : 0;
    unusable_ += std::isnan(x) ? 1 : 0;
    if (std::isfinite(x) && !(x >= nearest_)) nearest_ = x;  // NaN: none yet
  }
  return m;
}

FailureEstimate FailureCount::calc_binomial_estimate(double confidence) const {
  FailureEstimate e;
  e.runs = runs_;
  e.failures = failures_;
  e.nearest_margin = nearest_;
  e.unusable = unusable_;
  const std::int64_t usable = runs_ - unusable_;
  e.bounds = sampling::calc_binomial_bounds(failures_, usable, confidence);
  const double p = e.bounds.p;
  e.cov = p > 0.0 ? std::sqrt((1.0 - p) / (p * static_cast<double>(usable))) : std::nan("");
  e.status = runs_ > 0 ? "done" : "not_run";
  e.message = fmt::format("{} failures in {} usable runs ({} unusable)", failures_, usable, unusable_);
  e.untrusted = find_unusable_reason(unusable_, runs_);
  return e;
}

void write_failure_attributes(hid_t obj, const campaign::FailureOptions& f, const char* units_name) {
  using campaign::FailureKind;
  io::h5::write_string_attribute(obj, "failure_column", f.column);
  io::h5::write_string_attribute(obj, "failure_kind", f.kind == FailureKind::margin  ? "margin"
                                                      : f.kind == FailureKind::above ? "above"
                                                                                     : "below");
  io::h5::write_double_attribute(obj, "failure_threshold", f.kind == FailureKind::margin ? 0.0 : f.threshold);
  io::h5::write_string_attribute(obj, units_name, campaign::find_run_column_unit(f.column));
}

}  // namespace truss::methods
