#include "methods/stop_method.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "io/h5_util.hpp"

namespace truss::methods {

namespace {
bool is_percentile(const campaign::EnsembleOptions& e) {
  return e.stop_rule.target == sampling::StopTarget::percentile_bound;
}
}  // namespace

StopMethod::StopMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      plan_(sampling::SamplingMethod::monte_carlo, ctx.options.ensemble.stop_rule.max_runs, std::max(1, ctx.dims.total),
            ctx.options.ensemble.master_seed) {}

std::vector<std::string> StopMethod::observed_outputs() const {
  if (is_percentile(ctx_.options.ensemble)) return {ctx_.options.ensemble.stop_output};
  return {};
}

Proposal StopMethod::propose(std::int64_t round, const RoundRecords& previous) {
  const campaign::EnsembleOptions& e = ctx_.options.ensemble;
  if (round == 0) return {e.n_runs, {}};
  if (!decisions_.empty() && decisions_.back().state != sampling::StopState::more) return {};
  const auto ok = static_cast<std::int8_t>(sim::RunStatus::ok);
  for (std::size_t i = 0; i < previous.status.size(); ++i) {
    const bool is_ok = previous.status[i] == ok;
    failures_ += is_ok ? 0 : 1;
    if (is_percentile(e)) values_.push_back(is_ok ? previous.outputs.at(0)[i] : std::nan(""));
  }
  runs_ += static_cast<std::int64_t>(previous.status.size());
  decisions_.push_back(is_percentile(e) ? sampling::decide_percentile_stop(e.stop_rule, values_)
                                        : sampling::decide_probability_stop(e.stop_rule, failures_, runs_));
  const sampling::StopDecision& d = decisions_.back();
  if (d.state != sampling::StopState::more) return {};
  return {d.next_runs, {}};
}

void StopMethod::calc_uniforms(const RoundPlan&, std::int64_t run, double* u) const {
  if (ctx_.dims.total > 0) plan_.calc_uniforms(run, u);
}

void StopMethod::write_results(hid_t file, std::int64_t) const {
  using namespace io::h5;
  const campaign::EnsembleOptions& e = ctx_.options.ensemble;
  const sampling::StopRule& r = e.stop_rule;
  Handle g = create_group(file, "stop");
  write_string_attribute(g.get(), "target", sampling::to_string(r.target));
  write_string_attribute(g.get(), "output", e.stop_output);
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
  const std::string unit = is_percentile(e) ? campaign::find_run_column_unit(e.stop_output) : "1";
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
