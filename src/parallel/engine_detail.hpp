// Internals shared by the engine's parts: the message tags, a rank's messaging (Node), the sides
// of a round's schedule (engine.cpp: rank 0; worker.cpp) and a statistics rank's (stats_server.cpp).
#pragma once
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "parallel/engine.hpp"
#include "results/chunk_stats.hpp"

namespace truss::parallel::detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
double thread_cpu_s();  // the calling thread's CPU time, s

inline constexpr int kTagWork = 11;         // rank 0 -> worker: runs as (i64 first, i64 count); none: end of round
inline constexpr int kTagRecords = 12;      // any -> owner: sealed journal frames of its chunks' runs
inline constexpr int kTagDone = 13;         // worker -> rank 0: a batch is computed (its StatusCounts)
inline constexpr int kTagPart = 14;         // owner -> rank 0: a round part (results/chunk_messages.hpp)
inline constexpr int kTagChunk = 15;        // owner -> rank 0: a complete chunk's report (no summaries)
inline constexpr int kTagAskWindows = 16;   // owner -> statistics rank: the windows of its columns, please
inline constexpr int kTagSeed = 17;         // owner -> statistics rank: its columns' first windows (placement -1)
inline constexpr int kTagAskSeed = 18;      // statistics rank -> owner: send the first windows
inline constexpr int kTagPlacement = 19;    // rank 0 -> owner: where a chunk goes
inline constexpr int kTagWindows = 20;      // statistics rank -> owner: its columns' windows (placement -1)
inline constexpr int kTagFinished = 21;     // owner -> rank 0: its chunks written and synced
inline constexpr int kTagSummary = 22;      // owner -> statistics rank: a complete chunk's summaries of its columns
inline constexpr int kTagStats = 23;        // statistics rank -> rank 0: its columns' statistics (StatsPart)
inline constexpr int kTagDrained = 24;      // rank 0 -> worker: i64 round, whose last runs are handed out
inline constexpr int kTagLast = kTagDrained;

// A fatal error on any rank: the results file's temporary name removed (set_abort_removes; the
// journals keep every finished run for --resume), the job aborted (exit 3).
[[noreturn]] void abort_job(MPI_Comm comm, const char* where, const std::exception& e);
void set_abort_removes(const std::string& temporary);

// Sleeps between polls: min_us at first, doubling up to max_us; reset() after progress.
class Backoff {
 public:
  explicit Backoff(long min_us = 20, long max_us = 1000) : us_(min_us), min_us_(min_us), max_us_(max_us) {}
  void sleep();
  void reset() { us_ = min_us_; }

 private:
  long us_, min_us_, max_us_;
};

// A rank's messages: nonblocking sends it keeps until they complete (records counted against
// kMaxSendBytes), receives matched with MPI_Improbe and handled in the order they were matched,
// messages to itself through a queue (handled the same way), and the records of the runs it
// computes gathered per owner until they are sent.
class Node {
 public:
  using Handler = std::function<void(int tag, int source, std::string& bytes)>;
  // `status_offset`: where a record holds its status (its frame's byte kFrameHeader + it).
  Node(MPI_Comm comm, std::int64_t chunk_runs, std::size_t status_offset);
  std::size_t status_at() const { return results::kFrameHeader + status_offset_; }  // in a run's frame
  void set_rank0_chunks(std::vector<std::int64_t> chunks);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  std::int64_t chunk_runs() const { return chunk_runs_; }
  MPI_Comm comm() const { return comm_; }
  void set_handler(Handler h) { handler_ = std::move(h); }
  void send(int dest, int tag, std::string bytes);
  // Tests the sends, matches and receives messages, handles those complete; true if any was.
  bool poll();
  bool poll_local();  // the messages to itself only (rank 0 alone, before the session)
  bool flow_blocked() const { return record_bytes_ > kMaxSendBytes; }
  // While the rank's owner is behind, it takes no more records: their senders' sends stay in
  // flight, and those senders wait (flow_blocked).
  void pause_records(bool pause) { records_paused_ = pause; }
  double poll_s() const { return poll_s_; }  // wall time in poll()
  double mpi_s() const { return mpi_s_; }    //   of which in MPI calls

  // The owner of chunk k: rank 0 on one rank and for the chunks it restored, else 1 + k mod (P - 1).
  int owner_of(std::int64_t chunk) const;
  // A computed run's sealed frame, to its chunk's owner (sent by flush_records, called here once
  // kRecordsMessageBytes wait).
  void route(std::string_view frame, std::int64_t run);
  void flush_records();
  bool has_unsent_records() const;
  // Rank 0 between its own runs: while records it sent are in flight, the sends are tested
  // (MPI_Test), so that moving their bytes (over TCP the sender's writes) is paid with the runs
  // that made them, not in the next look at the messages. True if any completed.
  bool progress_records() { return record_bytes_ > 0 && test_sends(); }

 private:
  struct Out {
    std::string bytes;
    MPI_Request req = MPI_REQUEST_NULL;
    bool records = false;
  };
  struct In {
    std::string bytes;
    MPI_Request req = MPI_REQUEST_NULL;
    int tag = 0, source = 0;
  };
  bool test_sends();
  bool match();
  bool match_one(int tag);
  bool handle_received();

  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  std::int64_t chunk_runs_;
  std::size_t status_offset_;
  std::vector<std::int64_t> rank0_chunks_;  // sorted
  Handler handler_;
  std::list<Out> sends_;  // a list: the buffers must not move while a send is in flight
  std::size_t record_bytes_ = 0;
  std::list<In> received_;  // matched, in matching order (a list: the buffers stay put)
  std::deque<std::pair<int, std::string>> local_;
  std::map<int, std::string> unsent_;  // records per owner
  std::size_t unsent_bytes_ = 0;
  bool records_paused_ = false;
  double poll_s_ = 0.0, mpi_s_ = 0.0;
  bool in_poll_ = false, in_handler_ = false;
};

// Waits for a request while serving the rank's messages and chunks (`serve`: one unit of work,
// true if there was one).
void wait_serving(MPI_Request* req, Node& node, const std::function<bool()>& serve);

// The rank's chunk work in one call when nothing paces it: steps until this much wall time has
// passed (at least one step).
inline constexpr double kServeSliceS = 1e-3;

// A worker's part of round `plan`: batches in (node's work queue), their records to their owners,
// until the round is over. `serve(budget_s)`: the rank's owner work, steps until budget_s has passed
// (at least one), true if there was any.
class WorkQueue;
void run_worker_round(Node& node, WorkQueue& work, const methods::RoundPlan& plan, const Evaluate& evaluate,
                      const std::function<bool(double)>& serve);

// A statistics rank's side (results/chunk_stats.hpp): the owners' summaries of its columns
// merged; the windows they summarise against, the first from the first owner that asks for them,
// then after each merge the current ones back to that chunk's owner; once every chunk is merged,
// its columns' statistics to rank 0. Ranks 1 .. S on more than one rank (rank 0 keeps to the
// schedule and the chunks' placement), rank 0 alone on one rank and in a session that restored
// chunks before the others joined (results/chunk_stats.hpp: the statistics are the same wherever
// and in how many parts they are merged).
class StatsServer {
 public:
  StatsServer(Node& node, const campaign::RecordLayout& layout, results::ColumnRange columns)
      : node_(node), stats_(layout, columns) {}
  void handle(int tag, int source, std::string& bytes);
  static bool handles(int tag) { return tag == kTagAskWindows || tag == kTagSeed || tag == kTagSummary; }
  // Its statistics to rank 0 once the campaign's n_chunks are all merged: true when it sends them.
  bool send_if_complete(std::int64_t n_chunks);
  bool sent() const { return sent_; }

 private:
  void send_windows(int dest);
  Node& node_;
  results::ChunkStats stats_;
  std::vector<int> want_windows_;  // owners waiting for the first windows
  bool asked_seed_ = false, sent_ = false;
  results::ChunkReport summary_;   // its summaries' room used again
  double merge_cpu_s_ = 0.0;       // thread CPU in handle()
};

// The batches rank 0 sent a worker, in order; an empty one ends a round. And the last round whose
// runs rank 0 has all handed out (kTagDrained; by round, since with records paused the rank
// matches its messages tag by tag, so the notice may come after the round's end).
class WorkQueue {
 public:
  void push(std::string&& batch) { batches_.push_back(std::move(batch)); }
  bool empty() const { return batches_.empty(); }
  std::string pop() {
    std::string b = std::move(batches_.front());
    batches_.pop_front();
    return b;
  }
  void set_drained(std::int64_t round) { drained_round_ = std::max(drained_round_, round); }
  bool drained(std::int64_t round) const { return drained_round_ >= round; }

 private:
  std::deque<std::string> batches_;
  std::int64_t drained_round_ = -1;
};

}  // namespace truss::parallel::detail
