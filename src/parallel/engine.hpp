// The evaluation engine: the MPI layer knows one thing, evaluating a round of points (round r, run
// indices i..j) and returning their records. Every rank holds the same Method (methods/method.hpp);
// rank 0 asks it for round r's plan given round r - 1's records, journals the plan and broadcasts
// it; then the round's runs are scheduled dynamically over the ranks (a worker holds a second
// batch, so it never waits for rank 0; rank 0 computes runs itself between answering) and each
// rank computes a run's point from (plan, run index) alone.
//
// No rank handles every result. A run's record goes from the rank that computed it to the owner of
// its chunk of the results file (owner.hpp), which journals it, builds and encodes the chunk and
// writes its bytes where rank 0 placed them. Rank 0 works per batch (the schedule) and per chunk
// (round parts: the records a method reads; chunk reports: placement, messages); the chunks'
// statistics summaries go to the statistics ranks (ranks 1 .. S on more than one rank, each merging
// a range of the columns: results/chunk_stats.hpp StatsRanks).
//
// Progress without single-copy transports: no rank ever makes a blocking call for a message whose
// sender may be computing. Every rank matches its messages with MPI_Improbe, posts MPI_Imrecv for
// them and tests them between its own runs, and tests its outstanding sends; a rank stops
// computing while more than kMaxSendBytes of its records are in flight (the memory bound of a
// rank whose owners are slow to answer). Every wait (a broadcast, the end of a round) keeps
// serving the rank's chunks.
//
// Messages (engine_detail.hpp): a batch of run indices (rank 0 -> worker; none: the round is
// over), a batch done (worker -> rank 0), records (any rank -> owner: sealed journal frames,
// results/journal.hpp), round parts and chunk reports (owner -> rank 0), placements (rank 0 ->
// owner), statistics summaries, windows requests and first windows (owner -> statistics rank, of
// its columns), windows (statistics rank -> owner), an owner's end, and each statistics rank's
// streamed statistics (statistics rank -> rank 0).
#pragma once
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "methods/method.hpp"
#include "parallel/progress.hpp"
#include "results/campaign_file.hpp"
#include "results/chunk_messages.hpp"
#include "results/chunk_stats.hpp"
#include "results/journal.hpp"

namespace truss::parallel {

// A batch is remaining / (batches_per_rank * ranks) runs (guided self-scheduling: batches shrink
// as the round's end nears, so it stays balanced), at least kMinBatchS of runs at rank 0's measured
// wall time per run (the end's last batches are not single cheap runs, each a message), at most
// max_batch and a chunk of the results file.
struct EngineOptions {
  int max_batch = 4096;           // upper bound on runs per batch
  int batches_per_rank = 4;       // guided scheduling: batch = remaining / (batches_per_rank * ranks)
  double tick_interval_s = 0.25;  // how often rank 0 looks at the clock (journal syncs, progress)
  double flush_interval_s = 2.0;  // journal syncs
  // The campaign's cap on runs (campaign::calc_max_runs): a journal's round plan past it is refused.
  std::int64_t max_runs = std::numeric_limits<std::int64_t>::max();
  // Ranks that merge the statistics (find_stats_ranks); 0: one per kRanksPerStatisticsRank.
  int statistics_ranks = 0;
  std::string validate() const;
};

// A statistics rank's merge costs it about 1 us of CPU a Table-1 result (docs/benchmarks.md), its
// share S ways split; one per 32 ranks keeps it under a quarter of a rank's time for runs of 130 us
// at any rank count, for 2 S messages a chunk (a summary and the windows back, per statistics rank).
inline constexpr int kRanksPerStatisticsRank = 32;

// Where the statistics of `n_stats` columns are merged on `size` ranks: rank 0 alone on one rank
// and when it restores chunks before the others join (--resume); else ranks 1 .. S, S the asked
// count (0: ceil((size - 1) / kRanksPerStatisticsRank)), at most size - 1 and n_stats.
results::StatsRanks find_stats_ranks(int asked, int size, bool restores, std::size_t n_stats);

// Records a rank may have in flight to their owners before it waits for them to be received.
inline constexpr std::size_t kMaxSendBytes = std::size_t{32} << 20;
// A rank sends its computed records to their owners once this many bytes wait (and at a batch's end).
inline constexpr std::size_t kRecordsMessageBytes = std::size_t{256} << 10;
// The least work in a batch, in seconds of runs as rank 0 times its own (wall time: a run may wait
// rather than compute): a batch's messages cost rank 0 about as much as tens of costless runs'
// results; a batch of a millisecond's runs keeps the end of a round balanced to about that.
inline constexpr double kMinBatchS = 1e-3;

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

// What --resume found in the journals.
struct RestoreSummary {
  std::int64_t records = 0;        // runs restored
  std::vector<std::string> notes;  // damage dropped, rounds cut (one line each)
};

// Rank 0's bookkeeping of the campaign: the round plans (journaled), which runs are in (from the
// owners' round parts), the method's records, and the results file's chunks (placed as their
// owners report them).
class Collector {
 public:
  Collector(const campaign::RecordLayout& layout, methods::Method& method, results::Journal& journal,
            results::CampaignFile& file, Progress& progress, const EngineOptions& opts);
  // --resume: every frame of the journal and of the part journals of its sessions (read twice: to
  // check them and find the rounds complete, then to replay the kept records through `replay`,
  // rank 0's owner). A frame that passed its CRC but makes no sense (a run out of its round, twice
  // or from a rank the session did not have, a short payload, a NaN or negative time, a session
  // on no ranks) was not written by a crash: io::InputError naming the journal and the frame's
  // byte offset, and the journals stay as they were. A round that misses records (a host lost its
  // part journal's tail) ends the restored rounds: later plans and their records are cut from the
  // journals. Then the method proposes the journaled rounds again from the restored records:
  // io::InputError if it does not propose the same plans.
  struct RestoreSink {  // rank 0's chunks
    std::function<void(const methods::RoundPlan&)> round;  // each restored round, before its records
    std::function<void(std::string_view record, std::int64_t session)> record;
    std::function<void()> drain;  // rank 0's own messages handled (parts, chunks): memory stays bounded
  };
  RestoreSummary restore(const std::string& campaign_text, const RestoreSink& sink);
  // Journals this session's start and syncs the journal.
  void start_session(double unix_start, int n_ranks);
  // Round r's plan (rounds in order): the method's proposal from round r - 1's records (or the
  // journaled round that restore() proposed again), its digest journaled and written out (it
  // survives rank 0 before any rank computes a run of it), and the results file extended to its
  // runs. Returns the plan, which the engine sends to every rank.
  methods::RoundPlan plan_round(std::int64_t round, std::int64_t first_run);
  // Keep the whole plans of the rounds that hold these runs (kept_plans(), in round order): the
  // runs whose histories the file holds. Other plans are sent and dropped.
  void keep_plans_of(std::vector<std::int64_t> runs) { kept_runs_ = std::move(runs); }
  const std::vector<methods::RoundPlan>& kept_plans() const { return kept_plans_; }

  // The owners' messages.
  void add_part(const results::RoundPart& part);
  results::ChunkPlacement place(const results::ChunkReport& report);
  // The statistics rank's streamed statistics, once every chunk is merged (the end of the campaign).
  void set_stats(results::StreamedStats s) { stats_ = std::move(s); }
  const std::optional<results::StreamedStats>& stats() const { return stats_; }
  std::size_t n_observed() const { return observed_.size(); }
  const std::vector<std::size_t>& observed_fields() const { return observed_; }

  // `n` runs of status `status` computed (a batch's counts): what the progress counts, before
  // their records reach their owners' journals.
  void add_computed(std::int8_t status, std::int64_t n = 1);
  std::int64_t n_computed() const { return n_computed_; }
  const results::StatusCounts& computed_counts() const { return computed_counts_; }
  bool has(std::int64_t run) const {
    return run < static_cast<std::int64_t>(done_.size()) && done_[static_cast<std::size_t>(run)];
  }
  bool round_complete(const methods::RoundPlan& plan) const;
  std::int64_t n_done() const { return n_done_; }  // runs in the journals (round parts, restored)
  const results::StatusCounts& status_counts() const { return status_counts_; }
  const results::ResultStore& store() const { return file_.store(); }
  // Every flush interval (or now, with `sync`): a heartbeat and the journal synced (the owners push
  // the results file's pages to disk). Progress when due.
  void tick(bool sync);
  // Before the job is aborted (rank 0's fatal error): see CampaignFile::remove_temporary.
  void remove_temporary_file() noexcept { file_.remove_temporary(); }
  const SessionState& session() const { return st_; }
  const std::vector<methods::PlanDigest>& plans() const { return plans_; }  // journaled or planned so far

 private:
  struct Restore;
  methods::RoundPlan propose(std::int64_t round, std::int64_t first_run);  // round - 1's records to the method
  void count_in(std::int64_t run, std::size_t round, std::int8_t status);  // once per run
  void keep_if_asked(const methods::RoundPlan& plan);
  const campaign::RecordLayout& L_;
  methods::Method& method_;
  results::Journal& journal_;
  results::CampaignFile& file_;
  Progress& progress_;
  EngineOptions opts_;
  SessionState st_;
  std::vector<methods::PlanDigest> plans_;  // every round's, from the journal (the first n_journaled_) and new
  std::size_t n_journaled_ = 0;
  std::vector<methods::RoundPlan> restored_;  // the journaled rounds proposed again, until plan_round sends them
  std::vector<std::int64_t> kept_runs_;
  std::vector<methods::RoundPlan> kept_plans_;
  std::vector<std::size_t> observed_;                      // the record fields of method_.observed_outputs()
  bool reads_records_ = false;                             // method_.reads_records(): keep records_
  std::map<std::int64_t, methods::RoundRecords> records_;  // by round, for the method
  std::vector<bool> done_;                                 // by run: in a journal
  std::optional<results::StreamedStats> stats_;
  std::vector<std::int64_t> round_done_;                   // by round: runs in
  std::int64_t n_done_ = 0, n_computed_ = 0;
  results::StatusCounts status_counts_{}, computed_counts_{};
  std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now(), last_sync_ = wall0_;
};

class ChunkOwner;

// Collective over comm (run): the method's rounds, until it proposes none, then every chunk
// written. Every rank makes one and attaches its chunks' owner (rank 0 also its collector) before
// any message is handled; rank 0 may serve its own chunks alone before the session (--resume).
struct EngineResult {
  std::int64_t n_rounds = 0;                 // rounds with runs (rank 0 keeps their plans: Collector::plans)
  results::ScheduleSummary schedule;         // rank 0's (to the last record in)
  double last_chunks_s = 0.0;                // then, every chunk written (wall; part of the campaign's tail)
};
class Engine {
 public:
  // `status_offset`: where a record holds its status (RecordLayout), read from each run's frame.
  Engine(MPI_Comm comm, std::int64_t chunk_runs, std::size_t status_offset, const EngineOptions& opts);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;
  // What the rank's owner sends goes through this.
  std::function<void(int dest, int tag, std::string bytes)> sender();
  // `stats`: the ranks that merge the chunks' statistics, each a range of the columns (the same on
  // every rank).
  void attach(ChunkOwner& owner, Collector* collector, results::StatsRanks stats);
  // Rank 0 alone: its own messages and chunks handled until none is left.
  void serve_local();
  // The chunks rank 0 owns whatever the rank count (those it restored), the same on every rank.
  void set_rank0_chunks(std::vector<std::int64_t> chunks);
  EngineResult run(const Evaluate& evaluate);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Completes a request by testing it with sleeps in between (20 us doubling to 1 ms): a rank that
// only waits leaves the core to the others (Open MPI's blocking calls spin, which starves
// oversubscribed hosts).
void wait_idle(MPI_Request* req);
// MPI_Bcast of one int from rank 0, waiting with wait_idle.
int broadcast_int_idle(MPI_Comm comm, int v);

}  // namespace truss::parallel
