// The evaluation engine: the MPI layer knows one thing, evaluating a round of points (round r, run
// indices i..j) and returning their records. Every rank holds the same Method (methods/method.hpp);
// rank 0 asks it for round r's plan given round r - 1's records, journals the plan and broadcasts
// it; then the round's runs are scheduled dynamically over the ranks (a worker holds a second
// batch, so it never waits for rank 0; rank 0 computes runs itself between answering) and each
// rank computes a run's point from (plan, run index) alone. Rank 0's Collector journals and stores
// every record as it arrives and hands the method the round's records in run-index order.
//
// Progress without single-copy transports: no rank ever makes a blocking call for a message whose
// sender may be computing. Rank 0 matches a worker's result message with MPI_Improbe, posts
// MPI_Imrecv for it and tests it between its own runs; a worker tests its outstanding sends
// between its runs. A rendezvous message therefore moves a few fragments per run on both sides,
// over shared memory with or without CMA and over TCP alike. The next batch goes out as soon as
// the result message is matched, before its data has arrived.
//
// Messages: a work message (rank 0 -> worker) is the batch's run indices (i64 each; none: the
// round is over); a result message (worker -> rank 0) is the batch's records as sealed journal
// frames (results/journal.hpp), which rank 0 journals as they came.
#pragma once
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "methods/method.hpp"
#include "parallel/progress.hpp"
#include "results/campaign_file.hpp"
#include "results/journal.hpp"

namespace truss::parallel {

namespace detail {
struct FrameCheck;
}

struct EngineOptions {
  int max_batch = 32;             // upper bound on runs per batch: keeps the end of a round balanced
  int batches_per_rank = 4;       // guided scheduling: batch = remaining / (batches_per_rank * ranks)
  double tick_interval_s = 0.25;  // how often rank 0 looks at the clock (journal syncs, progress)
  double flush_interval_s = 2.0;  // journal syncs
  // The campaign's cap on runs (campaign::calc_max_runs): a journal's round plan past it is refused.
  std::int64_t max_runs = std::numeric_limits<std::int64_t>::max();
  std::string validate() const;
};

// Appends run `run`'s record, as a sealed journal frame (kind run), to `out`: the evaluation of one
// point of round `plan`, on any rank. Failed runs are records too; an exception aborts the job.
using Evaluate = std::function<void(const methods::RoundPlan& plan, std::int64_t run, std::string& out)>;

// What rank 0 carries from the journal into a session.
struct SessionState {
  std::int64_t session = 0;    // index of this invocation (0 unless resumed)
  double previous_wall_s = 0;  // wall time of the earlier sessions
  double first_start = 0;      // unix time of the first session
  double session_wall = 0;     // while reading the journal: the last heartbeat of the session read
};

// Rank 0: the path of a result from its frame to the file, and the rounds' bookkeeping. A record
// is checked against its round, appended to the journal, copied into its chunk of the results
// file and, if the method reads its outputs, into its round's records.
class Collector {
 public:
  Collector(const campaign::RecordLayout& layout, methods::Method& method, results::Journal& journal,
            results::CampaignFile& file, Progress& progress, const EngineOptions& opts);
  // --resume: every frame of the journal (Journal::open_existing) into the session state, the
  // round plans and the results file. A frame that passed its CRC but makes no sense (a run out of
  // its round, twice or from a rank the session did not have, a short payload, a NaN or negative
  // time, a session on no ranks) was not written by a crash: io::InputError naming the journal
  // and the frame's byte offset, and the journal stays as it was. Then the method proposes the
  // journaled rounds again from the restored records: io::InputError if it does not propose the
  // same plans (another program, or a method that depends on something else than its records).
  results::JournalScan restore();
  // Journals this session's start and syncs the journal.
  void start_session(double unix_start, int n_ranks);
  // Round r's plan: the method's proposal from round r - 1's records (or the journaled plan that
  // restore() checked), journaled, and the results file extended to its runs.
  methods::RoundPlan plan_round(std::int64_t round, std::int64_t first_run);
  // A run's sealed frame from round `plan`. Throws std::runtime_error for a frame that is not a
  // record of the round or a run stored before.
  void add_frame(std::string_view frame, const methods::RoundPlan& plan);
  const results::ResultStore& store() const { return file_.store(); }
  bool write_pending() const { return file_.store().write_pending(); }
  void write_next() { file_.store().write_next(); }
  // Every flush interval (or now, with `sync`): a heartbeat, the journal synced and the results
  // file's pages pushed to disk. Progress when due.
  void tick(bool sync);
  // Before the job is aborted (rank 0's fatal error): see CampaignFile::remove_temporary.
  void remove_temporary_file() noexcept { file_.remove_temporary(); }
  const SessionState& session() const { return st_; }
  double journal_s() const { return journal_s_; }
  const std::vector<methods::RoundPlan>& plans() const { return plans_; }  // journaled or planned so far

 private:
  void restore_frame(results::FrameKind kind, std::string_view payload, std::size_t offset);
  void restore_plan(const detail::FrameCheck& check);
  void restore_run(const detail::FrameCheck& check);
  methods::RoundPlan propose(std::int64_t round, std::int64_t first_run);  // round - 1's records to the method
  void observe(const campaign::RecordView& rec);
  const campaign::RecordLayout& L_;
  methods::Method& method_;
  results::Journal& journal_;
  results::CampaignFile& file_;
  Progress& progress_;
  EngineOptions opts_;
  SessionState st_;
  std::vector<methods::RoundPlan> plans_;  // every round's, from the journal (the first n_journaled_) and new
  std::size_t n_journaled_ = 0;
  std::int32_t session_ranks_ = 0;  // while restoring: the rank count of the session being read
  std::vector<std::size_t> observed_;                      // the record fields of method_.observed_outputs()
  bool reads_records_ = false;                             // method_.reads_records(): keep records_
  std::map<std::int64_t, methods::RoundRecords> records_;  // by round, for the method
  std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now(), last_sync_ = wall0_;
  double journal_s_ = 0.0;
};

// Collective over comm: the method's rounds, until it proposes none. `collector` is rank 0's (null
// on the other ranks). Returns every round's plan (on every rank) and, on rank 0, the schedule.
struct EngineResult {
  std::vector<methods::RoundPlan> plans;
  results::ScheduleSummary schedule;
};
EngineResult run_engine(MPI_Comm comm, const Evaluate& evaluate, Collector* collector, const EngineOptions& opts);

// Completes a request by testing it with sleeps in between (20 us doubling to 1 ms): a rank that
// only waits leaves the core to the others (Open MPI's blocking calls spin, which starves
// oversubscribed hosts).
void wait_idle(MPI_Request* req);
// MPI_Bcast of one int from rank 0, waiting with wait_idle.
int broadcast_int_idle(MPI_Comm comm, int v);

}  // namespace truss::parallel
