#include "methods/sweep_method.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "io/h5_util.hpp"
#include "methods/failure_count.hpp"
#include "methods/method_table.hpp"
#include "sampling/monotone_fit.hpp"
#include "util/bytes.hpp"

namespace truss::methods {

SweepMethod::SweepMethod(const campaign::CampaignContext& ctx, const MethodTable& methods)
    : ctx_(ctx), opt_(ctx.options.ensemble.method.as<SweepOptions>()), dims_(ctx.dims.dispersion_dims()) {
  if (ctx_.dims.design != dims_) throw std::logic_error("sweep: a campaign without a design axis");
  values_.resize(opt_.axis.n_design_values());
  for (std::size_t k = 0; k < values_.size(); ++k) {
    Value& v = values_[k];
    v.ctx = std::make_unique<campaign::CampaignContext>(campaign::calc_campaign_at(ctx.options, k));
    v.method = methods.make(*v.ctx);
    for (const std::string& name : v.method->observed_outputs()) {
      auto it = std::find(observed_.begin(), observed_.end(), name);
      if (it == observed_.end()) it = observed_.insert(observed_.end(), name);
      v.columns.push_back(static_cast<std::size_t>(it - observed_.begin()));
    }
  }
}

// Round r - 1's records, value by value (as the slices of last_), to each value's method, whose
// proposal for its next round they give; their rows of /runs are kept for its results.
void SweepMethod::hand_records(const RoundRecords& previous) {
  for (const Slice& s : last_) {
    Value& v = values_[s.value];
    const auto at = static_cast<std::size_t>(s.offset), n = static_cast<std::size_t>(s.plan.n_runs);
    if (at + n > previous.status.size()) throw std::logic_error("sweep: a round's records are fewer than its runs");
    RoundRecords r;
    if (v.method->reads_records()) {
      r.first_run = s.plan.first_run;
      r.status.assign(previous.status.begin() + static_cast<std::ptrdiff_t>(at),
                      previous.status.begin() + static_cast<std::ptrdiff_t>(at + n));
      for (std::size_t col : v.columns)
        r.outputs.emplace_back(previous.outputs.at(col).begin() + static_cast<std::ptrdiff_t>(at),
                               previous.outputs.at(col).begin() + static_cast<std::ptrdiff_t>(at + n));
    }
    for (std::size_t i = 0; i < n; ++i) v.rows.push_back(previous.first_run + static_cast<std::int64_t>(at + i));
    v.next = v.method->propose(++v.round, r);
  }
}

void SweepMethod::start_queued() {
  for (Value& v : values_)
    if (v.queued && !v.done && v.round < 0) v.next = v.method->propose(++v.round, {});
}

// The round: the next round of every queued value that is not done, in order of k.
Proposal SweepMethod::gather() {
  last_.clear();
  std::string state;
  std::size_t bytes = 0;  // at most: a round of motor runs holds hundreds of kB of points
  for (const Value& v : values_) bytes += 2 * sizeof(std::uint32_t) + RoundPlan::kHeaderBytes + v.next.state.size();
  state.reserve(bytes);
  std::int64_t total = 0;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    Value& v = values_[k];
    if (!v.queued || v.done) continue;
    if (v.next.n_runs == 0) {
      v.done = true;
      continue;
    }
    Slice s{static_cast<std::uint32_t>(k), {v.round, v.runs, v.next.n_runs, std::move(v.next.state)}, total};
    v.runs += s.plan.n_runs;
    total += s.plan.n_runs;
    util::put(state, s.value);
    const std::size_t length_at = state.size();
    util::put(state, std::uint32_t{0});
    s.plan.append_bytes(state);
    const auto length = static_cast<std::uint32_t>(state.size() - length_at - sizeof(std::uint32_t));
    util::put_at(state.data() + length_at, length);
    last_.push_back(std::move(s));
  }
  if (total == 0) return {};
  return {total, std::move(state)};
}

Proposal SweepMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) {
    for (std::size_t k = 0; k < opt_.axis.n_values(); ++k) values_[k].queued = true;
    refined_ = opt_.axis.refine == 0;
  } else {
    hand_records(previous);
  }
  start_queued();
  Proposal p = gather();
  if (p.n_runs == 0 && !refined_) {  // the listed values are done: refine around their allowable
    queue_refinement();
    start_queued();
    p = gather();
  }
  return p;
}

// The listed values' allowable picks the bracket (x_i, x_{i+1}) that holds it; its candidates run.
void SweepMethod::queue_refinement() {
  refined_ = true;
  const campaign::DesignAxis& axis = opt_.axis;
  const sampling::Allowable a = calc_sweep_verdict(ctx_.options, opt_, calc_value_results()).allowable;
  if (a.status != sampling::AllowableStatus::found) {
    refine_message_ = fmt::format("not refined: the listed values give no allowable ({}: {})",
                                  sampling::to_string(a.status), a.message);
    return;
  }
  std::size_t i = 0;
  while (i + 2 < axis.n_values() && axis.values[i + 1] <= a.value) ++i;
  refine_low_ = axis.values[i];
  refine_high_ = axis.values[i + 1];
  for (int j = 0; j < axis.refine; ++j) values_[axis.find_candidate_index(i, j)].queued = true;
  const std::string u = campaign::sweep_variable_units(ctx_.options);
  refine_message_ = fmt::format("refined between {:.6g} {} and {:.6g} {} (the bracket of the listed values' "
                                "allowable {:.6g} {}) with {} values",
                                refine_low_, u, refine_high_, u, a.value, u, axis.refine);
}

std::vector<std::size_t> SweepMethod::find_run_order() const {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < values_.size(); ++k)
    if (values_[k].queued) order.push_back(k);
  const campaign::DesignAxis& axis = opt_.axis;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return axis.find_value(a) < axis.find_value(b); });
  return order;
}

std::shared_ptr<const SweepMethod::Decoded> SweepMethod::decode(const RoundPlan& plan) const {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (decoded_ && decoded_->round == plan.round) return decoded_;
  }
  auto d = std::make_shared<Decoded>();
  d->round = plan.round;
  util::ByteReader r(plan.state, "a sweep round");
  std::int64_t offset = 0;
  while (r.left() > 0) {
    Slice s;
    s.value = r.get<std::uint32_t>();
    s.plan = RoundPlan::from_bytes(r.get_bytes(r.get<std::uint32_t>()));
    s.offset = offset;
    offset += s.plan.n_runs;
    if (s.value >= values_.size() || s.plan.n_runs < 1)
      throw std::runtime_error(fmt::format("a sweep round with value {} of {} runs", s.value, s.plan.n_runs));
    d->slices.push_back(std::move(s));
  }
  if (offset != plan.n_runs) throw std::runtime_error("a sweep round whose values' runs do not add up to its runs");
  std::lock_guard<std::mutex> lock(mutex_);
  decoded_ = d;
  return d;
}

void SweepMethod::calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const {
  const std::shared_ptr<const Decoded> d = decode(plan);
  const std::int64_t i = run - plan.first_run;
  const auto it = std::upper_bound(d->slices.begin(), d->slices.end(), i,
                                   [](std::int64_t x, const Slice& s) { return x < s.offset; });
  if (it == d->slices.begin() || i >= plan.n_runs)
    throw std::out_of_range(fmt::format("sweep: run {} not in its round", run));
  const Slice& s = *std::prev(it);
  values_[s.value].method->calc_uniforms(s.plan, s.plan.first_run + (i - s.offset), u);
  u[dims_] = (static_cast<double>(s.value) + 0.5) / static_cast<double>(values_.size());
}

std::vector<SweepMethod::ValueResult> SweepMethod::calc_value_results() const {
  const campaign::DesignAxis& axis = opt_.axis;
  const std::vector<std::size_t> order = find_run_order();
  std::vector<ValueResult> out(order.size());
  for (std::size_t row = 0; row < order.size(); ++row) {
    const std::size_t k = order[row];
    ValueResult& r = out[row];
    r.index = k;
    r.refinement = k >= axis.n_values();
    r.value = axis.find_value(k);
    r.seed = values_[k].ctx->options.ensemble.master_seed;
    if (std::optional<FailureEstimate> e = values_[k].method->calc_failure_estimate(opt_.confidence)) {
      r.estimate = std::move(*e);
      continue;
    }
    r.estimate.runs = values_[k].runs;
    r.estimate.status = "no_estimate";
    r.estimate.message = fmt::format("ensemble.method \"{}\" gives no estimate of the [failure] event's probability",
                                     opt_.inner.name());
  }
  return out;
}

namespace {

// "at 3.7 mm: why; at 4 mm: why" of the values whose estimates are untrusted, or empty.
std::string find_untrusted(const std::vector<SweepMethod::ValueResult>& values, const std::string& units) {
  std::string out;
  for (const SweepMethod::ValueResult& r : values)
    if (!r.estimate.untrusted.empty())
      out += fmt::format("{}at {:.6g} {}: {}", out.empty() ? "" : "; ", r.value, units, r.estimate.untrusted);
  return out;
}

// A value's estimate as the monotone fit reads it: a count (Monte Carlo, stop) is binomial over its
// usable runs; subset simulation's is lognormal with its CoV (the one [ensemble.subset] interval_cov names).
sampling::SweepEstimate to_sweep_estimate(const SweepMethod::ValueResult& r) {
  sampling::SweepEstimate e;
  e.x = r.value;
  e.untrusted = r.estimate.untrusted;
  if (r.estimate.failures >= 0) {
    e.kind = sampling::EstimateKind::binomial;
    e.failures = r.estimate.failures;
    e.runs = r.estimate.runs - r.estimate.unusable;
  } else {
    e.p = r.estimate.bounds.p;
    e.cov = r.estimate.cov;
  }
  return e;
}

}  // namespace

SweepVerdict calc_sweep_verdict(const campaign::CampaignOptions& c, const SweepOptions& opt,
                                const std::vector<SweepMethod::ValueResult>& values) {
  const std::string units = campaign::sweep_variable_units(c);
  SweepVerdict v;
  v.own_value = campaign::calc_sweep_own_value(c);
  if (const std::string untrusted = find_untrusted(values, units); !untrusted.empty()) {
    v.allowable.message = "not read: an estimate it would rest on cannot be trusted (" + untrusted + ")";
    v.verdict = "NOT ASSESSED";
    v.reason = "the evidence is untrusted: " + untrusted;
    return v;
  }
  std::vector<sampling::SweepEstimate> est;
  for (const SweepMethod::ValueResult& r : values) est.push_back(to_sweep_estimate(r));
  v.allowable = sampling::calc_monotone_fit(est, opt.calc_safe_side(), opt.target_probability, opt.confidence, units)
                    .allowable;
  const sampling::Allowable& a = v.allowable;
  if (a.status != sampling::AllowableStatus::found) {
    v.verdict = "NOT ASSESSED";
    const bool contradicted = a.status == sampling::AllowableStatus::contradicts_safe_side;
    v.reason = (contradicted ? "" : "no allowable in the swept range: ") + a.message;
    return v;
  }
  const bool pass = a.safe_side > 0 ? v.own_value >= a.value : v.own_value <= a.value;
  v.verdict = pass ? "PASS" : "FAIL";
  v.reason = fmt::format("the design's own value {:.6g} {} is on the {} side of the allowable {:.6g} {}", v.own_value,
                         units, pass ? "safe" : "unsafe", a.value, units);
  return v;
}

std::string SweepMethod::calc_not_assessed() const {
  const SweepVerdict v = calc_sweep_verdict(ctx_.options, opt_, calc_value_results());
  return v.verdict == "NOT ASSESSED" ? v.reason : std::string();
}

}  // namespace truss::methods
