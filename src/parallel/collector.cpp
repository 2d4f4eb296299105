// Rank 0's Collector (engine.hpp): the round plans, the runs in (from the owners' round parts), the
// method's records, the chunks placed. --resume is in restore.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel/engine.hpp"
#include "util/bytes.hpp"

namespace truss::parallel {

using results::FrameKind;

Collector::Collector(const campaign::RecordLayout& layout, methods::Method& method, results::Journal& journal,
                     results::CampaignFile& file, Progress& progress, const EngineOptions& opts)
    : L_(layout),
      method_(method),
      journal_(journal),
      file_(file),
      progress_(progress),
      opts_(opts),
      reads_records_(method.reads_records()) {
  for (const std::string& name : method.observed_outputs()) {
    const int f = layout.find_output(name);
    if (f < 0)
      throw std::invalid_argument(fmt::format("the method reads an output that records do not hold: {}", name));
    observed_.push_back(static_cast<std::size_t>(f));
  }
}

methods::RoundPlan Collector::propose(std::int64_t round, std::int64_t first_run) {
  methods::RoundRecords previous;
  if (const auto it = records_.find(round - 1); it != records_.end()) {
    previous = std::move(it->second);
    records_.erase(it);
  }
  methods::Proposal p = method_.propose(round, previous);
  if (p.n_runs < 0) throw std::logic_error(fmt::format("the method proposes {} runs for round {}", p.n_runs, round));
  return {round, first_run, p.n_runs, std::move(p.state)};
}

void Collector::start_session(double unix_start, int n_ranks) {
  if (st_.session == 0) st_.first_start = unix_start;
  std::string s;
  util::put(s, unix_start);
  util::put(s, static_cast<std::int32_t>(n_ranks));
  journal_.append(FrameKind::session, s);
  journal_.flush();
}

methods::RoundPlan Collector::plan_round(std::int64_t round, std::int64_t first_run) {
  const bool journaled = round < static_cast<std::int64_t>(n_journaled_);  // restore() proposed it again
  if (!journaled && round != static_cast<std::int64_t>(plans_.size()))
    throw std::logic_error(fmt::format("round {} planned after {} rounds", round, plans_.size()));
  methods::RoundPlan plan =
      journaled ? std::move(restored_[static_cast<std::size_t>(round)]) : propose(round, first_run);
  if (!journaled) {
    plans_.push_back(methods::PlanDigest::of(plan));
    keep_if_asked(plan);
    journal_.append(FrameKind::plan, plans_.back().to_bytes());
    journal_.write_out();  // before any rank journals a record of it
  }
  if (plan.n_runs > 0) {
    file_.store().extend(plan.end_run());
    done_.resize(std::max(done_.size(), static_cast<std::size_t>(plan.end_run())), false);  // never shrinks:
    round_done_.resize(std::max(round_done_.size(), static_cast<std::size_t>(round + 1)), 0);  // restored runs
    progress_.set_total(plan.end_run());
    progress_.set_stage(method_.progress_stage(), method_.run_cap());
  }
  return plan;
}

void Collector::keep_if_asked(const methods::RoundPlan& plan) {
  if (std::any_of(kept_runs_.begin(), kept_runs_.end(), [&](std::int64_t run) { return plan.contains(run); }))
    kept_plans_.push_back(plan);
}

void Collector::count_in(std::int64_t run, std::size_t round, std::int8_t status) {
  const auto i = static_cast<std::size_t>(run);
  if (done_[i]) return;
  if (status < 0 || status >= sim::kRunStatusCount)
    throw std::runtime_error(fmt::format("run {}: a status of {}", run, status));
  done_[i] = true;
  ++n_done_;
  ++round_done_[round];
  ++status_counts_[static_cast<std::size_t>(status)];
}

void Collector::add_computed(std::int8_t status, std::int64_t n) {
  if (status < 0 || status >= sim::kRunStatusCount || n < 0)
    throw std::runtime_error(fmt::format("{} runs with status {}", n, status));
  computed_counts_[static_cast<std::size_t>(status)] += n;
  n_computed_ += n;
}

// A round part's rows: in (the restored ones were counted as the journals were read), and, if
// the method reads them, in its round's records.
void Collector::add_part(const results::RoundPart& part) {
  const auto r = static_cast<std::size_t>(part.round);
  if (part.round < 0 || r >= plans_.size() || !plans_[r].contains(part.first_run) ||
      !plans_[r].contains(part.first_run + part.size() - 1) || part.outputs.size() != observed_.size())
    throw std::runtime_error(fmt::format("a round part of runs {} to {} in round {}", part.first_run,
                                         part.first_run + part.size() - 1, part.round));
  for (std::int64_t i = 0; i < part.size(); ++i)
    count_in(part.first_run + i, r, part.status[static_cast<std::size_t>(i)]);
  if (!reads_records_) return;
  methods::RoundRecords& rr = records_[part.round];
  if (rr.status.empty()) {  // the round's first part: its table, every status -1 (not in yet)
    const auto n = static_cast<std::size_t>(plans_[r].n_runs);
    rr.first_run = plans_[r].first_run;
    rr.status.assign(n, -1);
    rr.outputs.assign(observed_.size(), std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  }
  const auto at = static_cast<std::size_t>(part.first_run - rr.first_run);
  std::copy(part.status.begin(), part.status.end(), rr.status.begin() + static_cast<std::ptrdiff_t>(at));
  for (std::size_t k = 0; k < observed_.size(); ++k)
    std::copy(part.outputs[k].begin(), part.outputs[k].end(), rr.outputs[k].begin() + static_cast<std::ptrdiff_t>(at));
}

bool Collector::round_complete(const methods::RoundPlan& plan) const {
  const auto r = static_cast<std::size_t>(plan.round);
  return r < round_done_.size() && round_done_[r] == plan.n_runs;
}

results::ChunkPlacement Collector::place(const results::ChunkReport& report) {
  results::ChunkPlacement p;
  p.index = report.index;
  p.addresses = file_.store().place(report);
  return p;
}

void Collector::tick(bool sync) {
  const auto now = std::chrono::steady_clock::now();
  if (sync || std::chrono::duration<double>(now - last_sync_).count() >= opts_.flush_interval_s) {
    std::string s;
    util::put(s, std::chrono::duration<double>(now - wall0_).count());
    journal_.append(FrameKind::heartbeat, s);
    journal_.flush();
    last_sync_ = std::chrono::steady_clock::now();
  }
  progress_.update(n_computed_, [&] { return computed_counts_; });
}

}  // namespace truss::parallel
