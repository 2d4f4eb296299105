// A design sweep's results (sweep_method.hpp): /sweep with its values' estimates, the allowable and
// the verdict, each value's method's own results under /sweep/inner/<k>, and the terminal's lines.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "io/h5_util.hpp"
#include "methods/failure_count.hpp"
#include "methods/sweep_method.hpp"

namespace truss::methods {

namespace {

using namespace io::h5;

void write_allowable(hid_t g, const SweepVerdict& v, const std::string& units) {
  const sampling::Allowable& a = v.allowable;
  Handle h = create_group(g, "allowable");
  write_string_attribute(h.get(), "status", sampling::to_string(a.status));
  write_string_attribute(h.get(), "message", a.message);
  write_string_attribute(h.get(), "safe_side", a.safe_side > 0 ? "above" : a.safe_side < 0 ? "below" : "");
  write_string_attribute(h.get(), "method",
                         "the least (safe_side above) or greatest (below) design value whose one-sided upper "
                         "confidence bound on p is at or below the target: the upper bounds of the two values "
                         "bracketing the target interpolated linearly in ln p; estimate: the same crossing of p; "
                         "interval: the crossings of the two-sided interval's top and bottom");
  write_scalar(h.get(), "value", units, a.value);
  write_scalar(h.get(), "estimate", units, a.estimate);
  write_scalar(h.get(), "lower", units, a.lower);
  write_scalar(h.get(), "upper", units, a.upper);
  write_scalar(h.get(), "own_value", units, v.own_value);
  write_string_attribute(h.get(), "verdict", v.verdict);
  write_string_attribute(h.get(), "reason", v.reason);
}

void write_attributes(hid_t g, const campaign::CampaignOptions& c, const SweepOptions& opt) {
  const campaign::DesignAxis& axis = opt.axis;
  write_string_attribute(g, "variable", campaign::sweep_variable_name(c));
  write_string_attribute(g, "key", axis.key);
  write_string_attribute(g, "kind", axis.variable == campaign::SweepVariable::spread ? "spread" : "nominal");
  write_string_attribute(g, "units", campaign::sweep_variable_units(c));
  write_string_attribute(g, "inner_method", opt.inner.name());
  write_failure_attributes(g, *opt.failure_event(), "failure_units");
  write_double_attribute(g, "target_probability", opt.target_probability);
  write_double_attribute(g, "confidence", opt.confidence);
  write_int_attribute(g, "refine", axis.refine);
}

// A probability bound as written: inside [0, 1] (a lognormal interval's top can pass 1); NaN stays.
double clip_probability(double p) { return std::isnan(p) ? p : std::clamp(p, 0.0, 1.0); }

// One row per value: its estimate, as /sweep's columns.
void write_values(hid_t g, const std::vector<SweepMethod::ValueResult>& vr, const std::string& units) {
  const std::size_t n = vr.size();
  std::vector<double> value(n), p(n), cov(n), ub(n), lo(n), hi(n);
  std::vector<std::int64_t> runs(n), failures(n), unusable(n), seed(n), index(n), refinement(n);
  std::vector<std::string> status(n), message(n), untrusted(n);
  for (std::size_t k = 0; k < n; ++k) {
    const FailureEstimate& e = vr[k].estimate;
    value[k] = vr[k].value;
    p[k] = e.bounds.p;
    cov[k] = e.cov;
    ub[k] = clip_probability(e.bounds.upper_bound);
    lo[k] = clip_probability(e.bounds.lower);
    hi[k] = clip_probability(e.bounds.upper);
    unusable[k] = e.unusable;
    untrusted[k] = e.untrusted;
    runs[k] = e.runs;
    failures[k] = e.failures;
    seed[k] = static_cast<std::int64_t>(vr[k].seed);
    index[k] = static_cast<std::int64_t>(vr[k].index);
    refinement[k] = vr[k].refinement ? 1 : 0;
    status[k] = e.status;
    message[k] = e.message;
  }
  write_array(g, "values", units.c_str(), value.data(), n);
  write_array(g, "p", "1", p.data(), n);
  write_array(g, "cov", "1", cov.data(), n);
  write_array(g, "upper_bound", "1", ub.data(), n);
  write_array(g, "lower", "1", lo.data(), n);
  write_array(g, "upper", "1", hi.data(), n);
  write_array(g, "runs", "1", runs.data(), n);
  write_array(g, "failures", "1", failures.data(), n);
  write_array(g, "unusable", "1", unusable.data(), n);
  write_array(g, "master_seed", "1", seed.data(), n);
  write_array(g, "index", "1", index.data(), n);
  write_array(g, "refinement", "1", refinement.data(), n);
  write_strings(g, "status", status);
  write_strings(g, "message", message);
  write_strings(g, "untrusted", untrusted);
}

// An end of the allowable's interval: its value, or "beyond the swept values" (NaN).
std::string interval_end(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "beyond the swept values"; }

}  // namespace

Handle write_sweep_group(hid_t parent, const campaign::CampaignOptions& c, const SweepOptions& opt,
                         const std::vector<SweepMethod::ValueResult>& vr) {
  const std::string units = campaign::sweep_variable_units(c);
  Handle g = create_group(parent, "sweep");
  write_attributes(g.get(), c, opt);
  write_values(g.get(), vr, units);
  write_allowable(g.get(), calc_sweep_verdict(c, opt, vr), units);
  return g;
}

void SweepMethod::write_results(const ResultsPlace& place) const {
  const std::vector<ValueResult> vr = calc_value_results();
  Handle g = write_sweep_group(place.group, ctx_.options, opt_, vr);
  write_string_attribute(g.get(), "refine_message", refine_message_);
  write_double_attribute(g.get(), "refine_low", refine_low_);
  write_double_attribute(g.get(), "refine_high", refine_high_);
  Handle inner = create_group(g.get(), "inner");
  for (const ValueResult& r : vr) {
    const Value& v = values_[r.index];
    Handle at = create_group(inner.get(), std::to_string(r.index));
    write_int_attribute(at.get(), "master_seed", static_cast<std::int64_t>(r.seed));
    v.method->write_results({place.file, at.get(), place.n_runs, v.rows});
  }
}

std::string SweepMethod::calc_result_text() const {
  return calc_sweep_text(ctx_.options, opt_, calc_value_results(), refine_message_);
}

std::string calc_sweep_text(const campaign::CampaignOptions& c, const SweepOptions& opt,
                            const std::vector<SweepMethod::ValueResult>& vr, const std::string& refine_message) {
  using ValueResult = SweepMethod::ValueResult;
  const std::string name = campaign::sweep_variable_name(c), units = campaign::sweep_variable_units(c);
  const double conf = 100.0 * opt.confidence;
  const std::string how = opt.inner.name() == "importance" ? "one set of importance-sampling runs reweighted to each"
                                                            : opt.inner.name() + " at each";
  std::string t = fmt::format("[truss-campaign] sweep of {} ({} values, {}) for P({} fails), target {:g}:\n", name,
                              vr.size(), how, opt.failure_event()->column, opt.target_probability);
  for (const ValueResult& r : vr)
    t += fmt::format("[truss-campaign]   {} = {:.6g} {}: p = {:.4g} (CoV {:.3g}, {:g} % upper bound {:.4g}), {} runs, "
                     "{}{}{}\n",
                     name, r.value, units, r.estimate.bounds.p, r.estimate.cov, conf, r.estimate.bounds.upper_bound,
                     r.estimate.runs,
                     r.estimate.status, r.refinement ? " (refinement)" : "",
                     r.estimate.untrusted.empty() ? "" : ", untrusted: " + r.estimate.untrusted);
  if (opt.axis.refine > 0) t += fmt::format("[truss-campaign]   {}\n", refine_message);
  const SweepVerdict v = calc_sweep_verdict(c, opt, vr);
  const sampling::Allowable& a = v.allowable;
  if (a.status == sampling::AllowableStatus::found)
    t += fmt::format("[truss-campaign]   allowable: {} {} {:.6g} {} ({:g} % upper bound on p <= {:g}); estimate "
                     "{:.6g}, interval [{}, {}] {}; the campaign's own value {:.6g} {}\n",
                     name, a.safe_side > 0 ? ">=" : "<=", a.value, units, conf, opt.target_probability, a.estimate,
                     interval_end(a.lower), interval_end(a.upper), units, v.own_value, units);
  else
    t += fmt::format("[truss-campaign]   allowable: {}: {}\n", sampling::to_string(a.status), a.message);
  t += fmt::format("[truss-campaign] VERDICT: {} — {}\n", v.verdict, v.reason);
  return t;
}

}  // namespace truss::methods
