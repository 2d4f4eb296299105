// --resume (Collector::restore, engine.hpp): rank 0's journal and the part journals of its
// sessions, read twice. The first pass checks every frame and counts the records of each round;
// the rounds kept are those up to the first that misses records (a part journal whose host lost its
// unsynced tail), and what follows is cut from every journal. The second pass replays the kept
// records into rank 0's chunks, in the journals' order (rank 0's first, then each session's parts):
// a chunk's records lie in one part journal of a session, so chunks complete as they are read and
// memory stays bounded.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "io/scene_toml.hpp"
#include "parallel/engine.hpp"
#include "util/bytes.hpp"
#include "util/isal.hpp"

namespace truss::parallel {

using results::FrameKind;
namespace fs = std::filesystem;

namespace {

// The checks of one journal frame. A frame that passed its CRC but holds what no campaign writes (a
// crash tears the last frame, it does not make one up) is refused, naming the journal and the
// frame's byte offset.
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

// One journal file of the restore: where its rounds start, where it is cut.
struct JournalFile {
  std::string path;
  std::int64_t session = -1;  // a part's session (-1: rank 0's journal)
  int rank = 0;
  std::vector<std::pair<std::int64_t, std::size_t>> round_starts;  // (round, offset of its first record)
  std::size_t cut = SIZE_MAX;
};

}  // namespace

struct Collector::Restore {
  Restore(Collector& collector, const RestoreSink& s) : c(collector), sink(s) {}
  Collector& c;
  const RestoreSink& sink;
  std::uint32_t crc = 0;
  std::vector<std::int32_t> session_ranks;  // by session
  std::vector<std::size_t> plan_offsets, session_offsets;
  std::vector<std::int64_t> count;  // records by round
  std::vector<bool> seen;           // by run
  std::vector<JournalFile> files;   // rank 0's, then the parts

  void frame_main(FrameKind kind, const FrameCheck& check);
  void plan(const FrameCheck& check);
  void record(JournalFile& f, const FrameCheck& check, std::int32_t ranks, bool part);
  void scan_parts(const std::string& output);
  std::size_t find_last_round() const;
  void cut(std::size_t last, RestoreSummary& sum);
  void replay(results::Journal& j, JournalFile& f);
};

void Collector::Restore::frame_main(FrameKind kind, const FrameCheck& check) {
  SessionState& st = c.st_;
  if (kind != FrameKind::session && st.session == 0) check.refuse("a record before the first session record");
  if (kind == FrameKind::session) {
    check.size(sizeof(double) + sizeof(std::int32_t), "session");
    const double start = check.seconds(util::get_at<double>(check.payload.data()), "a session start at unix time");
    const auto ranks = util::get_at<std::int32_t>(check.payload.data() + sizeof(double));
    if (ranks < 1) check.refuse(fmt::format("a session on {} ranks", ranks));
    session_ranks.push_back(ranks);
    session_offsets.push_back(check.offset);
    if (st.session == 0) st.first_start = start;
    st.previous_wall_s += st.session_wall;
    st.session_wall = 0.0;
    ++st.session;
  } else if (kind == FrameKind::heartbeat) {
    check.size(sizeof(double), "heartbeat");
    const double wall = check.seconds(util::get_at<double>(check.payload.data()), "a heartbeat (session wall time)");
    if (wall < st.session_wall)
      check.refuse(fmt::format("a heartbeat of {} s after one of {} s in the same session", wall, st.session_wall));
    st.session_wall = wall;
  } else if (kind == FrameKind::plan) {
    plan(check);
  } else {
    record(files.front(), check, session_ranks.back(), false);
  }
}

void Collector::Restore::plan(const FrameCheck& check) {
  methods::PlanDigest p;
  try {
    p = methods::PlanDigest::from_bytes(check.payload);
  } catch (const std::exception& e) {
    check.refuse(e.what());
  }
  std::vector<methods::PlanDigest>& plans = c.plans_;
  const std::int64_t first = plans.empty() ? 0 : plans.back().end_run();
  // Before anything is allocated for its runs: a plan within the campaign's cap (first <= the cap
  // by the earlier plans' check, so the difference does not overflow).
  if (p.first_run == first && p.n_runs > c.opts_.max_runs - first)
    check.refuse(fmt::format("round {} plans {} runs from run {}, past the campaign's cap of {} runs", p.round,
                             p.n_runs, p.first_run, c.opts_.max_runs));
  if (p.round != static_cast<std::int64_t>(plans.size()) || p.first_run != first || p.n_runs < 0)
    check.refuse(fmt::format("round {} (runs {} to {}) does not follow round {}", p.round, p.first_run,
                             p.end_run() - 1, static_cast<std::int64_t>(plans.size()) - 1));
  plans.push_back(p);
  plan_offsets.push_back(check.offset);
  count.push_back(0);
  seen.resize(static_cast<std::size_t>(p.end_run()), false);
}

// A run record of a session on `ranks` ranks. In a part journal a record of a round not planned (a
// host that synced its part before rank 0 synced the plan) is cut, not refused.
void Collector::Restore::record(JournalFile& f, const FrameCheck& check, std::int32_t ranks, bool part) {
  if (const std::string e = c.L_.check(check.payload); !e.empty())
    check.refuse(fmt::format("not a run record of this campaign ({}, {} bytes)", e, check.payload.size()));
  const campaign::RecordView rec(check.payload, c.L_);
  const std::int64_t run = rec.run(), round = rec.round();
  const auto& plans = c.plans_;
  const bool planned = round >= 0 && round < static_cast<std::int64_t>(plans.size());
  if (!(part && round >= static_cast<std::int64_t>(plans.size())) &&
      (!planned || !plans[static_cast<std::size_t>(round)].contains(run)))
    check.refuse(fmt::format("run index {} out of range (round {}; the journal's rounds have runs 0 to {})", run,
                             round, plans.empty() ? -1 : plans.back().end_run() - 1));
  if (!f.round_starts.empty() && round < f.round_starts.back().first)
    check.refuse(fmt::format("a record of round {} after one of round {}", round, f.round_starts.back().first));
  if (f.round_starts.empty() || round > f.round_starts.back().first) f.round_starts.emplace_back(round, check.offset);
  if (!planned) return;
  if (rec.rank() < 0 || rec.rank() >= ranks)
    check.refuse(fmt::format("run {} computed on rank {} in a session on {} rank{}", run, rec.rank(), ranks,
                             ranks > 1 ? "s" : ""));
  if (const double w = rec.wall_time_s(); !(std::isfinite(w) && w >= 0.0))
    check.refuse(fmt::format("run {}: a wall time of {} s", run, w));
  if (seen[static_cast<std::size_t>(run)]) check.refuse(fmt::format("run {} recorded twice", run));
  seen[static_cast<std::size_t>(run)] = true;
  ++count[static_cast<std::size_t>(round)];
}

// The part journals of every session (a rank that built no chunk left none).
void Collector::Restore::scan_parts(const std::string& output) {
  for (std::size_t s = 0; s < session_ranks.size(); ++s)
    for (int r = 1; r < session_ranks[s]; ++r) {
      JournalFile f;
      f.path = results::part_journal_path(output, static_cast<std::int64_t>(s), r);
      f.session = static_cast<std::int64_t>(s);
      f.rank = r;
      std::error_code ec;
      // None (a rank that built no chunk), or cut before its header was written out: no record.
      if (!fs::exists(fs::symlink_status(f.path, ec)) || fs::file_size(f.path, ec) < results::kPartHeaderBytes)
        continue;
      results::Journal j = results::Journal::open_part(f.path, crc, f.session, r);
      FrameKind kind{};
      std::string_view payload;
      std::size_t offset = 0;
      while (j.next_frame(kind, payload, offset)) {
        const FrameCheck check{f.path, offset, payload};
        if (kind != FrameKind::run) check.refuse("a part journal holds run records only");
        record(f, check, session_ranks[s], true);
      }
      files.push_back(std::move(f));
    }
}

// The last round kept: the first that misses records, else the last planned.
std::size_t Collector::Restore::find_last_round() const {
  const auto& plans = c.plans_;
  for (std::size_t r = 0; r < plans.size(); ++r)
    if (count[r] < plans[r].n_runs) return r;
  return plans.empty() ? 0 : plans.size() - 1;
}

void Collector::Restore::cut(std::size_t last, RestoreSummary& sum) {
  auto& plans = c.plans_;
  if (last + 1 < plans.size()) {
    const std::size_t at = plan_offsets[last + 1];
    if (session_offsets.back() > at)
      throw io::InputError(fmt::format("error: --resume: {}: a session started after round {}, which misses runs; "
                                       "the journal is inconsistent; start over with --force", files[0].path, last));
    files[0].cut = at;
    sum.notes.push_back(fmt::format("round {} misses {} of its {} runs (a journal lost its last records): rounds {} "
                                    "to {} are computed again", last, plans[last].n_runs - count[last],
                                    plans[last].n_runs, last + 1, plans.size() - 1));
    plans.resize(last + 1);
  }
  for (std::size_t k = 1; k < files.size(); ++k)
    for (const auto& [round, offset] : files[k].round_starts)
      if (round > static_cast<std::int64_t>(last)) {
        files[k].cut = offset;
        break;
      }
}

// The kept records of one journal into rank 0's chunks.
void Collector::Restore::replay(results::Journal& j, JournalFile& f) {
  FrameKind kind{};
  std::string_view payload;
  std::size_t offset = 0;
  std::int64_t session = f.session, n = 0;
  while (j.next_frame(kind, payload, offset) && offset < f.cut) {
    if (kind == FrameKind::session) ++session;
    if (kind != FrameKind::run) continue;
    const campaign::RecordView rec(payload, c.L_);
    c.count_in(rec.run(), static_cast<std::size_t>(rec.round()), rec.status());
    c.add_computed(rec.status());
    sink.record(payload, session);
    if (++n % 64 == 0) sink.drain();
  }
  sink.drain();
}

RestoreSummary Collector::restore(const std::string& campaign_text, const RestoreSink& sink) {
  Restore r{*this, sink};
  r.crc = util::calc_crc32(campaign_text);
  std::string output = journal_.path();
  output.resize(output.size() - std::string(".journal").size());
  r.files.emplace_back().path = journal_.path();
  {
    results::Journal main = results::Journal::open_existing(journal_.path(), campaign_text);
    FrameKind kind{};
    std::string_view payload;
    std::size_t offset = 0;
    while (main.next_frame(kind, payload, offset)) r.frame_main(kind, {journal_.path(), offset, payload});
  }
  st_.previous_wall_s += st_.session_wall;
  st_.session_wall = 0.0;
  r.scan_parts(output);
  RestoreSummary sum;
  const std::size_t last = r.find_last_round();
  r.cut(last, sum);
  for (const methods::PlanDigest& p : plans_) {
    file_.store().extend(p.end_run());
    done_.resize(static_cast<std::size_t>(p.end_run()), false);
    if (p.n_runs > 0) sink.round({p.round, p.first_run, p.n_runs, {}});
  }
  round_done_.assign(plans_.size(), 0);
  n_journaled_ = plans_.size();
  r.replay(journal_, r.files[0]);
  std::vector<results::Journal> parts;
  for (std::size_t k = 1; k < r.files.size(); ++k) {
    JournalFile& f = r.files[k];
    r.replay(parts.emplace_back(results::Journal::open_part(f.path, r.crc, f.session, f.rank)), f);
  }
  for (std::size_t k = 0; k < n_journaled_; ++k) {  // a journaled round follows a round that is complete
    methods::RoundPlan& p = restored_.emplace_back(propose(static_cast<std::int64_t>(k), plans_[k].first_run));
    keep_if_asked(p);
    if (!(methods::PlanDigest::of(p) == plans_[k]))
      throw io::InputError(fmt::format("error: --resume: {}: round {} of the journal is not the round the method "
                                       "proposes now from the same records (another program?); start over with "
                                       "--force", journal_.path(), k));
  }
  // Only now, every check passed: the journals cut after their last kept record (damage, rounds cut).
  for (std::size_t k = 0; k < r.files.size(); ++k) {
    results::Journal& j = k == 0 ? journal_ : parts[k - 1];
    if (const std::string d = j.finish_reading(r.files[k].cut).describe(r.files[k].path); !d.empty())
      sum.notes.push_back(d);
  }
  sum.records = n_done_;
  return sum;
}

}  // namespace truss::parallel
