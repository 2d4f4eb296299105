#include "methods/sweep_method.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "io/h5_util.hpp"
#include "methods/fixed_design.hpp"
#include "methods/stop_method.hpp"
#include "methods/subset_method.hpp"
#include "util/bytes.hpp"

namespace truss::methods {

namespace {

// The inner method, by its options' type (the rows of builtin_methods()).
SweepMethod::Inner inner_of(const campaign::CampaignOptions& c) {
  const campaign::MethodOptions& o = c.ensemble.method.options();
  if (dynamic_cast<const SubsetMethodOptions*>(&o) != nullptr) return SweepMethod::Inner::subset;
  if (dynamic_cast<const StopOptions*>(&o) != nullptr) return SweepMethod::Inner::stop;
  if (dynamic_cast<const DesignOptions*>(&o) != nullptr) return SweepMethod::Inner::monte_carlo;
  throw std::logic_error("sweep: ensemble.method \"" + c.ensemble.method.name() + "\" has no inner method");
}

const campaign::FailureOptions& failure_of(const campaign::CampaignOptions& c) {
  const campaign::FailureOptions* f = c.ensemble.method.options().failure_event();
  if (f == nullptr) throw std::logic_error("sweep: a method without a [failure] event");
  return *f;
}

const char* inner_name(SweepMethod::Inner i) {
  return i == SweepMethod::Inner::subset ? "subset" : i == SweepMethod::Inner::stop ? "stop" : "monte_carlo";
}

}  // namespace

SweepMethod::SweepMethod(const campaign::CampaignContext& ctx)
    : ctx_(ctx),
      inner_(inner_of(ctx.options)),
      failure_(failure_of(ctx.options)),
      dims_(ctx.dims.dispersion_dims()) {
  const campaign::CampaignOptions& c = ctx_.options;
  if (!c.sweep.active || ctx_.dims.design != dims_) throw std::logic_error("sweep: a campaign without [sweep]");
  if (ctx_.record.find_output(failure_.column) < 0)
    throw std::logic_error(fmt::format("sweep: {} is not a float64 output of the record", failure_.column));
  values_.resize(c.sweep.n_design_values());
  for (std::size_t k = 0; k < values_.size(); ++k) {
    const campaign::CampaignOptions at = campaign::calc_campaign_at(c, k);
    Value& v = values_[k];
    v.seed = at.ensemble.master_seed;
    if (inner_ == Inner::subset) v.subset = at.ensemble.method.as<SubsetMethodOptions>().calc_sim_options(at);
    if (inner_ != Inner::subset)
      v.plan.emplace(sampling::SamplingMethod::monte_carlo, campaign::calc_max_runs(at), dims_, v.seed);
  }
}

// Value k's next round: the inner method of calc_campaign_at(c, k).
Proposal SweepMethod::propose_value(std::size_t k, Slice& slice) {
  Value& v = values_[k];
  slice.value = static_cast<std::uint32_t>(k);
  slice.local_first = v.runs;
  const bool first = !v.started;
  v.started = true;
  if (inner_ == Inner::subset) {
    if (first) v.sim.emplace(v.subset);
    if (v.sim->done()) return {};
    const sampling::SubsetRound& r = v.sim->round();
    if (r.first_evaluation != v.runs)
      throw std::logic_error(fmt::format("sweep: value {}'s round starts at evaluation {}, run {}", k,
                                         r.first_evaluation, v.runs));
    return {r.n_points, r.encode()};
  }
  const campaign::EnsembleOptions& e = ctx_.options.ensemble;
  if (first) return {e.n_runs, {}};
  if (inner_ == Inner::monte_carlo || v.decisions.back().state != sampling::StopState::more) return {};
  return {v.decisions.back().next_runs, {}};
}

void SweepMethod::take_records(std::size_t k, const RoundRecords& r) {
  Value& v = values_[k];
  const std::vector<double> m = SubsetMethod::calc_margins(failure_, r);
  v.runs += static_cast<std::int64_t>(m.size());
  for (double x : m)
    if (std::isfinite(x) && !(x >= v.nearest_margin)) v.nearest_margin = x;  // NaN: none yet
  if (inner_ == Inner::subset) {
    v.sim->add_margins(m);
    return;
  }
  for (double x : m) v.failures += x <= 0.0 ? 1 : 0;
  if (inner_ == Inner::stop)
    v.decisions.push_back(sampling::decide_probability_stop(ctx_.options.ensemble.method.as<StopOptions>().rule,
                                                            v.failures, v.runs));
}

Proposal SweepMethod::propose(std::int64_t round, const RoundRecords& previous) {
  if (round == 0) {
    for (std::size_t k = 0; k < values_.size(); ++k) {
      Value& v = values_[k];
      v.sim.reset();
      v.runs = v.failures = 0;
      v.nearest_margin = std::nan("");
      v.decisions.clear();
      v.queued = k < ctx_.options.sweep.n_values();
      v.started = v.done = false;
    }
    refined_ = ctx_.options.sweep.refine == 0;
    refine_message_.clear();
    refine_low_ = refine_high_ = std::nan("");
  } else {
    std::size_t at = 0;
    for (const Slice& s : last_) {  // the previous round's records, value by value
      RoundRecords r;
      r.first_run = s.local_first;
      const auto n = static_cast<std::size_t>(s.n_runs);
      if (at + n > previous.status.size()) throw std::logic_error("sweep: a round's records are fewer than its runs");
      r.status.assign(previous.status.begin() + static_cast<std::ptrdiff_t>(at),
                      previous.status.begin() + static_cast<std::ptrdiff_t>(at + n));
      r.outputs.emplace_back(previous.outputs.at(0).begin() + static_cast<std::ptrdiff_t>(at),
                             previous.outputs.at(0).begin() + static_cast<std::ptrdiff_t>(at + n));
      take_records(s.value, r);
      at += n;
    }
  }
  Proposal p = propose_queued();
  if (p.n_runs == 0 && !refined_) {  // the listed values are done: refine around their allowable
    queue_refinement();
    p = propose_queued();
  }
  return p;
}

// The round: the next round of every queued value that is not done, in order of k.
Proposal SweepMethod::propose_queued() {
  last_.clear();
  std::string state;
  std::int64_t total = 0;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    if (!values_[k].queued || values_[k].done) continue;
    Slice s;
    const Proposal p = propose_value(k, s);
    if (p.n_runs == 0) {
      values_[k].done = true;
      continue;
    }
    s.n_runs = p.n_runs;
    s.offset = total;
    util::put(state, s.value);
    util::put(state, s.local_first);
    util::put(state, s.n_runs);
    util::put(state, static_cast<std::uint32_t>(p.state.size()));
    state += p.state;
    total += p.n_runs;
    last_.push_back(std::move(s));
  }
  if (total == 0) return {};
  return {total, state};
}

// The listed values' allowable picks the bracket (x_i, x_{i+1}) that holds it; its candidates run.
void SweepMethod::queue_refinement() {
  refined_ = true;
  const campaign::SweepOptions& sw = ctx_.options.sweep;
  const sampling::Allowable a = calc_allowable();
  if (a.status != sampling::AllowableStatus::found) {
    refine_message_ = fmt::format("not refined: the listed values give no allowable ({}: {})",
                                  sampling::to_string(a.status), a.message);
    return;
  }
  std::size_t i = 0;
  while (i + 2 < sw.n_values() && sw.values[i + 1] <= a.value) ++i;
  refine_low_ = sw.values[i];
  refine_high_ = sw.values[i + 1];
  for (int j = 0; j < sw.refine; ++j) values_[sw.find_candidate_index(i, j)].queued = true;
  refine_message_ = fmt::format("refined between {:.6g} and {:.6g} {} (the bracket of the listed values' allowable "
                                "{:.6g}) with {} values",
                                refine_low_, refine_high_, campaign::sweep_variable_units(ctx_.options), a.value,
                                sw.refine);
}

std::vector<std::size_t> SweepMethod::find_run_order() const {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < values_.size(); ++k)
    if (values_[k].queued) order.push_back(k);
  const campaign::SweepOptions& sw = ctx_.options.sweep;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return sw.find_value(a) < sw.find_value(b); });
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
    s.local_first = r.get<std::int64_t>();
    s.n_runs = r.get<std::int64_t>();
    s.state = std::string(r.get_bytes(r.get<std::uint32_t>()));
    s.offset = offset;
    offset += s.n_runs;
    if (s.value >= ctx_.options.sweep.n_design_values() || s.n_runs < 1)
      throw std::runtime_error(fmt::format("a sweep round with value {} of {} runs", s.value, s.n_runs));
    if (inner_ == Inner::subset)
      s.round = std::make_shared<const sampling::SubsetRound>(sampling::SubsetRound::decode(s.state, dims_));
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
  const Value& v = values_[s.value];
  const std::int64_t local = i - s.offset;
  if (inner_ == Inner::subset) sampling::calc_round_uniforms(v.subset, *s.round, local, u);
  else v.plan->calc_uniforms(s.local_first + local, u);
  u[dims_] = (static_cast<double>(s.value) + 0.5) / static_cast<double>(ctx_.options.sweep.n_design_values());
}

std::vector<SweepMethod::ValueResult> SweepMethod::calc_value_results() const {
  const campaign::SweepOptions& sw = ctx_.options.sweep;
  const std::vector<std::size_t> order = find_run_order();
  std::vector<ValueResult> out(order.size());
  for (std::size_t row = 0; row < order.size(); ++row) {
    const std::size_t k = order[row];
    const Value& v = values_[k];
    ValueResult& r = out[row];
    r.index = k;
    r.refinement = k >= sw.n_values();
    r.value = sw.find_value(k);
    r.seed = v.seed;
    r.runs = v.runs;
    if (inner_ == Inner::subset) {
      if (!v.sim) continue;
      const sampling::SubsetSummary s = v.sim->calc_summary();
      r.cov = s.cov_bound;
      r.bounds = sampling::calc_lognormal_bounds(s.p, s.cov_bound, sw.confidence);
      r.bounds.p = s.p;
      r.status = sampling::to_string(s.status);
      r.message = s.message;
      continue;
    }
    r.failures = v.failures;
    r.bounds = sampling::calc_binomial_bounds(v.failures, v.runs, sw.confidence);
    const double p = r.bounds.p;
    r.cov = p > 0.0 ? std::sqrt((1.0 - p) / (p * static_cast<double>(v.runs))) : std::nan("");
    if (inner_ == Inner::stop && !v.decisions.empty()) {
      r.status = sampling::to_string(v.decisions.back().state);
      r.message = v.decisions.back().reason;
    } else {
      r.status = v.runs > 0 ? "done" : "not_run";
      r.message = fmt::format("{} failures in {} runs", v.failures, v.runs);
    }
  }
  return out;
}

sampling::Allowable SweepMethod::calc_allowable() const {
  std::vector<double> x;
  std::vector<sampling::ProbabilityBounds> b;
  sampling::NearestMargins nearest{{}, campaign::find_run_column_unit(failure_.column)};
  for (const ValueResult& r : calc_value_results()) {
    x.push_back(r.value);
    b.push_back(r.bounds);
    nearest.margin.push_back(values_[r.index].nearest_margin);
  }
  return sampling::find_allowable(x, b, ctx_.options.sweep.target_probability,
                                  campaign::sweep_variable_units(ctx_.options), nearest);
}

namespace {

using namespace io::h5;

void write_allowable(hid_t g, const sampling::Allowable& a, const std::string& units, double own) {
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
  write_scalar(h.get(), "own_value", units, own);
  const bool pass = a.status == sampling::AllowableStatus::found && (a.safe_side > 0 ? own >= a.value : own <= a.value);
  write_string_attribute(h.get(), "verdict", a.status != sampling::AllowableStatus::found ? "NOT ASSESSED"
                                             : pass                                     ? "PASS"
                                                                                        : "FAIL");
}

}  // namespace

void SweepMethod::write_inner(hid_t group, std::size_t k) const {
  const Value& v = values_[k];
  Handle g = create_group(group, std::to_string(k));
  write_int_attribute(g.get(), "master_seed", static_cast<std::int64_t>(v.seed));
  if (inner_ == Inner::subset && v.sim) {
    const sampling::SubsetSummary s = v.sim->calc_summary();
    write_string_attribute(g.get(), "status", sampling::to_string(s.status));
    write_scalar(g.get(), "p", "1", s.p);
    write_scalar(g.get(), "cov", "1", s.cov);
    write_scalar(g.get(), "cov_lineage", "1", s.cov_lineage);
    write_scalar(g.get(), "cov_bound", "1", s.cov_bound);
    write_scalar(g.get(), "runs", "1", s.runs);
    const std::size_t n = s.levels.size();
    std::vector<double> threshold(n), prob(n);
    std::vector<std::int64_t> runs(n);
    for (std::size_t l = 0; l < n; ++l) {
      threshold[l] = s.levels[l].threshold;
      prob[l] = s.levels[l].probability;
      runs[l] = s.levels[l].runs;
    }
    const std::string unit = campaign::find_run_column_unit(failure_.column);
    write_array(g.get(), "level_threshold", unit.c_str(), threshold.data(), n);
    write_array(g.get(), "level_probability", "1", prob.data(), n);
    write_array(g.get(), "level_runs", "1", runs.data(), n);
    return;
  }
  const std::size_t n = v.decisions.size();
  std::vector<std::int64_t> runs(n);
  std::vector<double> est(n), lo(n), hi(n);
  std::vector<std::string> state(n);
  for (std::size_t i = 0; i < n; ++i) {
    runs[i] = v.decisions[i].runs;
    est[i] = v.decisions[i].estimate;
    lo[i] = v.decisions[i].lo;
    hi[i] = v.decisions[i].hi;
    state[i] = sampling::to_string(v.decisions[i].state);
  }
  write_scalar(g.get(), "runs", "1", v.runs);
  write_scalar(g.get(), "failures", "1", v.failures);
  if (inner_ != Inner::stop) return;
  write_array(g.get(), "stop_runs", "1", runs.data(), n);
  write_array(g.get(), "stop_estimate", "1", est.data(), n);
  write_array(g.get(), "stop_lower", "1", lo.data(), n);
  write_array(g.get(), "stop_upper", "1", hi.data(), n);
  write_strings(g.get(), "stop_state", state);
}

void SweepMethod::write_results(hid_t file, std::int64_t) const {
  const campaign::CampaignOptions& c = ctx_.options;
  const std::vector<ValueResult> vr = calc_value_results();
  const std::string units = campaign::sweep_variable_units(c);
  const campaign::FailureOptions& f = failure_;
  Handle g = create_group(file, "sweep");
  write_string_attribute(g.get(), "variable", campaign::sweep_variable_name(c));
  write_string_attribute(g.get(), "key", c.sweep.key);
  write_string_attribute(g.get(), "kind", c.sweep.variable == campaign::SweepVariable::spread ? "spread" : "nominal");
  write_string_attribute(g.get(), "units", units);
  write_string_attribute(g.get(), "inner_method", inner_name(inner_));
  write_string_attribute(g.get(), "failure_column", f.column);
  write_string_attribute(g.get(), "failure_kind", f.kind == campaign::FailureKind::margin  ? "margin"
                                                  : f.kind == campaign::FailureKind::above ? "above"
                                                                                           : "below");
  write_double_attribute(g.get(), "failure_threshold", f.kind == campaign::FailureKind::margin ? 0.0 : f.threshold);
  write_string_attribute(g.get(), "failure_units", campaign::find_run_column_unit(f.column));
  write_double_attribute(g.get(), "target_probability", c.sweep.target_probability);
  write_double_attribute(g.get(), "confidence", c.sweep.confidence);
  write_int_attribute(g.get(), "refine", c.sweep.refine);
  write_string_attribute(g.get(), "refine_message", refine_message_);
  write_double_attribute(g.get(), "refine_low", refine_low_);
  write_double_attribute(g.get(), "refine_high", refine_high_);
  const std::size_t n = vr.size();
  std::vector<double> value(n), p(n), cov(n), ub(n), lo(n), hi(n);
  std::vector<std::int64_t> runs(n), failures(n), seed(n), index(n), refinement(n);
  std::vector<std::string> status(n), message(n);
  for (std::size_t k = 0; k < n; ++k) {
    value[k] = vr[k].value;
    p[k] = vr[k].bounds.p;
    cov[k] = vr[k].cov;
    ub[k] = vr[k].bounds.upper_bound;
    lo[k] = vr[k].bounds.lower;
    hi[k] = vr[k].bounds.upper;
    runs[k] = vr[k].runs;
    failures[k] = vr[k].failures;
    seed[k] = static_cast<std::int64_t>(vr[k].seed);
    index[k] = static_cast<std::int64_t>(vr[k].index);
    refinement[k] = vr[k].refinement ? 1 : 0;
    status[k] = vr[k].status;
    message[k] = vr[k].message;
  }
  write_array(g.get(), "values", units.c_str(), value.data(), n);
  write_array(g.get(), "p", "1", p.data(), n);
  write_array(g.get(), "cov", "1", cov.data(), n);
  write_array(g.get(), "upper_bound", "1", ub.data(), n);
  write_array(g.get(), "lower", "1", lo.data(), n);
  write_array(g.get(), "upper", "1", hi.data(), n);
  write_array(g.get(), "runs", "1", runs.data(), n);
  write_array(g.get(), "failures", "1", failures.data(), n);
  write_array(g.get(), "master_seed", "1", seed.data(), n);
  write_array(g.get(), "index", "1", index.data(), n);
  write_array(g.get(), "refinement", "1", refinement.data(), n);
  write_strings(g.get(), "status", status);
  write_strings(g.get(), "message", message);
  write_allowable(g.get(), calc_allowable(), units, campaign::calc_sweep_own_value(c));
  Handle inner = create_group(g.get(), "inner");
  for (const ValueResult& r : vr) write_inner(inner.get(), r.index);
}

namespace {

// An end of the allowable's interval: its value, or "beyond the swept values" (NaN).
std::string interval_end(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "beyond the swept values"; }

}  // namespace

std::string SweepMethod::calc_result_text() const {
  const campaign::CampaignOptions& c = ctx_.options;
  const std::string name = campaign::sweep_variable_name(c), units = campaign::sweep_variable_units(c);
  const double conf = 100.0 * c.sweep.confidence;
  std::string t = fmt::format("[truss-campaign] sweep of {} ({} values, {} at each) for P({} fails), target {:g}:\n",
                              name, calc_value_results().size(), inner_name(inner_), failure_.column,
                              c.sweep.target_probability);
  for (const ValueResult& r : calc_value_results())
    t += fmt::format("[truss-campaign]   {} = {:.6g} {}: p = {:.4g} ({:g} % upper bound {:.4g}), {} runs, {}{}\n",
                     name, r.value, units, r.bounds.p, conf, r.bounds.upper_bound, r.runs, r.status,
                     r.refinement ? " (refinement)" : "");
  if (c.sweep.refine > 0) t += fmt::format("[truss-campaign]   {}\n", refine_message_);
  const sampling::Allowable a = calc_allowable();
  if (a.status == sampling::AllowableStatus::found)
    t += fmt::format("[truss-campaign]   allowable: {} {} {:.6g} {} ({:g} % upper bound on p <= {:g}); estimate "
                     "{:.6g}, interval [{}, {}] {}; the campaign's own value {:.6g} {}\n",
                     name, a.safe_side > 0 ? ">=" : "<=", a.value, units, conf, c.sweep.target_probability,
                     a.estimate, interval_end(a.lower), interval_end(a.upper), units,
                     campaign::calc_sweep_own_value(c), units);
  else
    t += fmt::format("[truss-campaign]   allowable: {}: {}\n", sampling::to_string(a.status), a.message);
  return t;
}

}  // namespace truss::methods
