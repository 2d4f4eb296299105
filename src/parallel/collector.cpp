// Rank 0's Collector (engine.hpp): a result's frame into the journal, the results file and the
// method's round records; the round plans; --resume from the journal.
#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "io/scene_toml.hpp"
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

results::JournalScan Collector::restore() {
  FrameKind kind{};
  std::string_view payload;
  std::size_t offset = 0;
  while (journal_.next_frame(kind, payload, offset)) restore_frame(kind, payload, offset);
  st_.previous_wall_s += st_.session_wall;
  st_.session_wall = 0.0;
  n_journaled_ = plans_.size();
  for (std::size_t r = 0; r < n_journaled_; ++r) {  // a journaled round follows a round that is complete
    const methods::RoundPlan p = propose(static_cast<std::int64_t>(r), plans_[r].first_run);
    if (!(p == plans_[r]))
      throw io::InputError(fmt::format("error: --resume: {}: round {} of the journal is not the round the method "
                                       "proposes now from the same records (another program?); start over with "
                                       "--force", journal_.path(), r));
  }
  return journal_.finish_reading();
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

namespace detail {

// The checks of one journal frame on --resume. A frame that passed its CRC but holds what no
// campaign writes (a crash tears the last frame, it does not make one up) is refused, naming the
// journal and the frame's byte offset.
struct FrameCheck {
  const std::string& path;
  std::size_t offset;
  std::string_view payload;
  [[noreturn]] void refuse(const std::string& what) const {
    throw io::InputError(fmt::format("error: --resume: {}: record at byte {}: {}; the journal is inconsistent; "
                                     "start over with --force", path, offset, what));
  }
  void size(std::size_t n, const char* what) const {
    if (payload.size() != n) refuse(fmt::format("a {} record of {} bytes (expected {})", what, payload.size(), n));
  }
  // A clock reading or a duration: finite and not negative.
  double seconds(double v, const char* what) const {
    if (!(std::isfinite(v) && v >= 0.0)) refuse(fmt::format("{} of {} s", what, v));
    return v;
  }
};

}  // namespace detail

using detail::FrameCheck;

// One journal frame into the session state, the plans or the results file. Every frame follows a
// session record (start_session writes one before anything else).
void Collector::restore_frame(FrameKind kind, std::string_view payload, std::size_t offset) {
  const FrameCheck check{journal_.path(), offset, payload};
  if (kind != FrameKind::session && st_.session == 0) check.refuse("a record before the first session record");
  if (kind == FrameKind::session) {
    check.size(sizeof(double) + sizeof(std::int32_t), "session");
    const double start = check.seconds(util::get_at<double>(payload.data()), "a session start at unix time");
    session_ranks_ = util::get_at<std::int32_t>(payload.data() + sizeof(double));
    if (session_ranks_ < 1) check.refuse(fmt::format("a session on {} ranks", session_ranks_));
    if (st_.session == 0) st_.first_start = start;
    st_.previous_wall_s += st_.session_wall;
    st_.session_wall = 0.0;
    ++st_.session;
  } else if (kind == FrameKind::heartbeat) {
    check.size(sizeof(double), "heartbeat");
    const double wall = check.seconds(util::get_at<double>(payload.data()), "a heartbeat (session wall time)");
    if (wall < st_.session_wall)
      check.refuse(fmt::format("a heartbeat of {} s after one of {} s in the same session", wall, st_.session_wall));
    st_.session_wall = wall;
  } else if (kind == FrameKind::plan) {
    restore_plan(check);
  } else {
    restore_run(check);
  }
}

void Collector::restore_plan(const FrameCheck& check) {
  methods::RoundPlan p;
  try {
    p = methods::RoundPlan::from_bytes(check.payload);
  } catch (const std::exception& e) {
    check.refuse(e.what());
  }
  const std::int64_t first = plans_.empty() ? 0 : plans_.back().end_run();
  // Before anything is allocated for its runs: a plan within the campaign's cap (first <= the cap
  // by the earlier plans' check, so the difference does not overflow).
  if (p.first_run == first && p.n_runs > opts_.max_runs - first)
    check.refuse(fmt::format("round {} plans {} runs from run {}, past the campaign's cap of {} runs", p.round,
                             p.n_runs, p.first_run, opts_.max_runs));
  if (p.round != static_cast<std::int64_t>(plans_.size()) || p.first_run != first || p.n_runs < 0)
    check.refuse(fmt::format("round {} (runs {} to {}) does not follow round {}", p.round, p.first_run,
                             p.end_run() - 1, static_cast<std::int64_t>(plans_.size()) - 1));
  plans_.push_back(p);
  file_.store().extend(p.end_run());
}

void Collector::restore_run(const FrameCheck& check) {
  if (const std::string e = L_.check(check.payload); !e.empty())
    check.refuse(fmt::format("not a run record of this campaign ({}, {} bytes)", e, check.payload.size()));
  const campaign::RecordView rec(check.payload, L_);
  const std::int64_t run = rec.run(), round = rec.round();
  if (round < 0 || round >= static_cast<std::int64_t>(plans_.size()) ||
      !plans_[static_cast<std::size_t>(round)].contains(run))
    check.refuse(fmt::format("run index {} out of range (round {}; the journal's rounds have runs 0 to {})", run,
                             round, plans_.empty() ? -1 : plans_.back().end_run() - 1));
  if (rec.rank() < 0 || rec.rank() >= session_ranks_)
    check.refuse(fmt::format("run {} computed on rank {} in a session on {} ranks", run, rec.rank(), session_ranks_));
  if (const double w = rec.wall_time_s(); !(std::isfinite(w) && w >= 0.0))
    check.refuse(fmt::format("run {}: a wall time of {} s", run, w));
  if (file_.store().has(run)) check.refuse(fmt::format("run {} recorded twice", run));
  file_.store().add(rec, std::max<std::int64_t>(0, st_.session - 1));
  observe(rec);
  while (file_.store().write_pending()) file_.store().write_next();  // memory bounded as in a session
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
  const methods::RoundPlan plan = journaled ? plans_[static_cast<std::size_t>(round)] : propose(round, first_run);
  if (!journaled) {
    journal_.append(FrameKind::plan, plan.to_bytes());
    plans_.push_back(plan);
  }
  if (plan.n_runs > 0) {
    file_.store().extend(plan.end_run());
    progress_.set_total(plan.end_run());
    progress_.set_stage(method_.progress_stage(), method_.run_cap());
  }
  return plan;
}

void Collector::observe(const campaign::RecordView& rec) {
  if (!reads_records_) return;
  const std::int64_t round = rec.round();
  methods::RoundRecords& r = records_[round];
  if (r.status.empty()) {  // the round's first record: its table, every status -1 (not in yet)
    const methods::RoundPlan& plan = plans_.at(static_cast<std::size_t>(round));
    const auto n = static_cast<std::size_t>(plan.n_runs);
    r.first_run = plan.first_run;
    r.status.assign(n, -1);
    r.outputs.assign(observed_.size(), std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  }
  const auto i = static_cast<std::size_t>(rec.run() - r.first_run);
  r.status[i] = rec.status();
  for (std::size_t k = 0; k < observed_.size(); ++k) r.outputs[k][i] = rec.f64(observed_[k]);
}

void Collector::add_frame(std::string_view frame, const methods::RoundPlan& plan) {
  const results::Frame f = results::read_frame(frame);
  if (f.kind != FrameKind::run || f.bytes.size() != frame.size())
    throw std::runtime_error(fmt::format("a result of {} bytes is not one run frame", frame.size()));
  if (const std::string e = L_.check(f.payload); !e.empty()) throw std::runtime_error(e);
  const campaign::RecordView rec(f.payload, L_);
  if (rec.round() != plan.round || !plan.contains(rec.run()))
    throw std::runtime_error(fmt::format("a record of run {} (round {}) in round {} (runs {} to {})", rec.run(),
                                         rec.round(), plan.round, plan.first_run, plan.end_run() - 1));
  if (file_.store().has(rec.run())) throw std::runtime_error(fmt::format("run {} received twice", rec.run()));
  const auto t0 = std::chrono::steady_clock::now();
  journal_.append_frame(frame);
  journal_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  file_.store().add(rec, st_.session);
  observe(rec);
}

void Collector::tick(bool sync) {
  const auto now = std::chrono::steady_clock::now();
  if (sync || std::chrono::duration<double>(now - last_sync_).count() >= opts_.flush_interval_s) {
    std::string s;
    util::put(s, std::chrono::duration<double>(now - wall0_).count());
    journal_.append(FrameKind::heartbeat, s);
    journal_.flush();
    file_.start_writeback();  // the results file's pages go to disk during the run, not in the tail
    last_sync_ = std::chrono::steady_clock::now();
  }
  const results::ResultStore& store = file_.store();
  progress_.update(store.n_done(), [&] { return store.status_counts(); });
}

}  // namespace truss::parallel
