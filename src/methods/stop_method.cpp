#include "methods/stop_method.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "campaign/method_input.hpp"
#include "io/h5_util.hpp"

namespace truss::methods {

const campaign::OptionTable<StopOptions>& StopOptions::table() {
  using campaign::kAnyNumber;
  using S = StopOptions;
  static const campaign::OptionTable<S> t{
      "ensemble.stop", "sequential stopping: Monte Carlo rounds from n_runs until the target holds, or max_runs", {
          TRUSS_OPTION_CHOICE(S, "target", rule.target, "what must hold",
                              campaign::choice_names(sampling::kStopTargetNames)),
          campaign::written_if(TRUSS_OPTION_TEXT(S, "output", output, "percentile_bound: a float64 column of /runs"),
                               +[](const S& o) { return !o.output.empty(); }),
          TRUSS_OPTION_REAL(S, "level", rule.level, "1", kAnyNumber, "percentile_bound: the quantile, in (0, 1)"),
          TRUSS_OPTION_REAL(S, "width", rule.width, "1", kAnyNumber,
                            "(bound - estimate) / estimate; the probability targets' half-width (absolute, or over p)"),
          TRUSS_OPTION_REAL(S, "confidence", rule.confidence, "1", kAnyNumber, "of the bound or interval, in (0, 1)"),
          TRUSS_OPTION_INT(S, "max_runs", rule.max_runs, "1", kAnyNumber, "cap on the runs of all rounds"),
      }};
  return t;
}

std::unique_ptr<campaign::MethodOptions> StopOptions::parse(const campaign::MethodInput& in) {
  auto o = std::make_unique<StopOptions>();
  campaign::read_method_table(in, table(), *o);
  campaign::read_failure_event(in, o->failure);
  return o;
}

std::string StopOptions::validate(const campaign::CampaignOptions& c) const {
  const campaign::EnsembleOptions& e = c.ensemble;
  if (e.sampling != sampling::SamplingMethod::monte_carlo)
    return fmt::format("ensemble.sampling: [ensemble.stop] adds runs round by round, which only Monte Carlo points "
                       "allow (\"{}\" fixes its design for n_runs)", sampling::to_string(e.sampling));
  if (const std::string err = rule.validate(); !err.empty()) return "ensemble.stop." + err;
  if (e.n_runs > rule.max_runs)
    return fmt::format("ensemble.stop.max_runs: {} is below the first round's ensemble.n_runs = {}", rule.max_runs,
                       e.n_runs);
  if (is_percentile() && campaign::find_run_column_unit(output).empty())
    return fmt::format("ensemble.stop.output: \"{}\" is not a float64 column of /runs (e.g. peak_drive_torque_Nm)",
                       output);
  if (failure.kind != campaign::FailureKind::none && is_percentile())
    return "ensemble.stop.target: \"percentile_bound\" estimates a percentile, not a probability: a [failure] event "
           "goes with a probability target (probability_half_width, probability_relative_half_width)";
  if (!is_percentile() && !output.empty())
    return "ensemble.stop.output: the probability targets count the runs that are not ok; output goes with "
           "target = \"percentile_bound\"";
  return campaign::validate_sampling(c);
}

std::string StopOptions::to_toml() const {
  return "[ensemble.stop]\n" + campaign::write_options(table(), *this) + "\n" + campaign::failure_toml(failure);
}

StopMethod::StopMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      opt_(ctx.options.ensemble.method.as<StopOptions>()),
      plan_(sampling::SamplingMethod::monte_carlo, opt_.rule.max_runs, std::max(1, ctx.dims.total),
            ctx.options.ensemble.master_seed) {
  if (opt_.failure.kind != campaign::FailureKind::none) event_.emplace(opt_.failure);
}

std::vector<std::string> StopMethod::observed_outputs() const {
  if (opt_.is_percentile()) return {opt_.output};
  if (event_) return {opt_.failure.column};
  return {};
}

Proposal StopMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) return {ctx_.options.ensemble.n_runs, {}};
  if (!decisions_.empty() && decisions_.back().state != sampling::StopState::more) return {};
  const auto ok = static_cast<std::int8_t>(sim::RunStatus::ok);
  for (std::size_t i = 0; i < previous.status.size(); ++i) {
    const bool is_ok = previous.status[i] == ok;
    failures_ += is_ok ? 0 : 1;
    if (opt_.is_percentile()) values_.push_back(is_ok ? previous.outputs.at(0)[i] : std::nan(""));
  }
  runs_ += static_cast<std::int64_t>(previous.status.size());
  if (event_) {  // the runs that fail the event, not those that are not ok
    event_->add(previous);
    failures_ = event_->failures();
  }
  decisions_.push_back(opt_.is_percentile() ? sampling::decide_percentile_stop(opt_.rule, values_)
                                             : sampling::decide_probability_stop(opt_.rule, failures_, runs_));
  const sampling::StopDecision& d = decisions_.back();
  if (d.state != sampling::StopState::more) return {};
  return {d.next_runs, {}};
}

void StopMethod::calc_uniforms(const RoundPlan&, std::int64_t run, double* u) const {
  if (ctx_.dims.total > 0) plan_.calc_uniforms(run, u);
}

std::optional<FailureEstimate> StopMethod::calc_failure_estimate(double confidence) const {
  if (!event_) return std::nullopt;
  FailureEstimate e = event_->calc_binomial_estimate(confidence);
  if (!decisions_.empty()) {
    e.status = sampling::to_string(decisions_.back().state);
    e.message = decisions_.back().reason;
  }
  return e;
}

void StopMethod::write_results(const ResultsPlace& place) const {
  using namespace io::h5;
  const sampling::StopRule& r = opt_.rule;
  Handle g = create_group(place.group, "stop");
  write_string_attribute(g.get(), "target", sampling::to_string(r.target));
  write_string_attribute(g.get(), "output", opt_.output);
  write_double_attribute(g.get(), "level", r.level);
  write_double_attribute(g.get(), "width", r.width);
  write_double_attribute(g.get(), "confidence", r.confidence);
  write_int_attribute(g.get(), "max_runs", r.max_runs);
  write_string_attribute(g.get(), "state", decisions_.empty() ? "" : sampling::to_string(decisions_.back().state));
  write_string_attribute(g.get(), "reason", decisions_.empty() ? "" : decisions_.back().reason);
  const std::size_t n = decisions_.size();
  std::vector<std::int64_t> runs(n), used(n);
  std::vector<double> est(n), lo(n), hi(n), achieved(n);
  std::vector<std::string> state(n), reason(n);
  for (std::size_t k = 0; k < n; ++k) {
    const sampling::StopDecision& d = decisions_[k];
    runs[k] = d.runs;
    used[k] = d.used;
    est[k] = d.estimate;
    lo[k] = d.lo;
    hi[k] = d.hi;
    achieved[k] = d.achieved;
    state[k] = sampling::to_string(d.state);
    reason[k] = d.reason;
  }
  const std::string unit = opt_.is_percentile() ? campaign::find_run_column_unit(opt_.output) : "1";
  write_array(g.get(), "runs", "1", runs.data(), n);
  write_array(g.get(), "used", "1", used.data(), n);
  write_array(g.get(), "estimate", unit.c_str(), est.data(), n);
  write_array(g.get(), "lower", unit.c_str(), lo.data(), n);
  write_array(g.get(), "upper", unit.c_str(), hi.data(), n);
  write_array(g.get(), "achieved_width", "1", achieved.data(), n);
  write_strings(g.get(), "state", state);
  write_strings(g.get(), "reason", reason);
}

std::string StopMethod::calc_result_text() const {
  std::string t;
  for (std::size_t k = 0; k < decisions_.size(); ++k)
    t += fmt::format("[truss-campaign] stop rule after round {} ({} runs): {}: {}\n", k, decisions_[k].runs,
                     sampling::to_string(decisions_[k].state), decisions_[k].reason);
  return t;
}

}  // namespace truss::methods
