// Dynamic scheduling of independent runs over MPI ranks. Rank 0 owns the list of runs to do and
// hands out batches on request; every rank, rank 0 included, computes runs. A worker always holds
// a second batch while it computes one (its result message is its request for the next), so it
// never waits for rank 0. Rank 0 computes one run at a time and answers requests in between.
// Results are opaque byte strings (one per run) that reach rank 0's on_result in completion order;
// the caller stores them by run index, so nothing downstream depends on the order.
//
// Progress without single-copy transports: no rank ever makes a blocking call for a message whose
// sender may be computing. Rank 0 matches a worker's result message with MPI_Improbe, posts
// MPI_Imrecv for it and tests it between its own runs; a worker tests its outstanding sends
// between its runs. A rendezvous message (larger than the eager limit) therefore moves a few
// fragments per run on both sides, over shared memory with or without CMA and over TCP alike,
// and rank 0 never stalls for a whole batch of a peer. The next batch goes out as soon as the
// result message is matched, before its data has arrived.
#pragma once
#include <mpi.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace truss::parallel {

struct ScheduleOptions {
  int max_batch = 32;              // upper bound on runs per batch: keeps the end of the campaign balanced
  int batches_per_rank = 4;        // guided scheduling: batch = remaining / (batches_per_rank * ranks)
  double tick_interval_s = 0.25;   // how often rank 0 calls on_tick (progress, journal flushes)
  // Rank 0, once every worker holds its first two batches: set-up that need not keep them waiting
  // (allocating the result store, restoring a journal). No result is delivered before it returns.
  std::function<void()> on_started;
  // Side jobs (optional): rank 0's take_job fills a job that rides with the next non-empty batch a
  // worker gets (false: none waiting); the worker runs do_job on it before the batch's runs and
  // sends the output with the batch's results, which reach rank 0's on_job_done. The campaign
  // uses them to have workers encode (compress) the results file's chunks.
  std::function<bool(std::string& job)> take_job;
  // output lies inside owner's owner_bytes (the whole message, which a deferred write keeps alive)
  std::function<void(std::shared_ptr<const char[]> owner, std::size_t owner_bytes, std::string_view output)> on_job_done;
  std::function<void(std::string_view job, std::string& output)> do_job;
  // Rank 0 with no runs left and nothing received: runs one waiting side job itself (false: none).
  std::function<bool()> do_local_job;
  // Rank 0 (optional): side jobs may still appear from results already delivered (made on another
  // thread), or wait: the schedule goes on until they are out and back, as for the ones given out.
  std::function<bool()> side_jobs_pending;
  // Rank 0 (optional): a worker's results message as a whole, in place of one on_result call per
  // result (rank 0's own runs still go through on_result): `results` point into `message`, which
  // the callee may keep (the journal writes the results from it: no copy on rank 0).
  std::function<void(std::shared_ptr<const char[]> message, const std::vector<std::string_view>& results)> on_message;
  // Rank 0: a job's buffer once its message has gone (optional): take_job's memory back for reuse.
  std::function<void(std::string&& buffer)> on_job_sent;
  std::string validate() const;
};

// Rank 0's view (zeros elsewhere). Times are wall (steady clock) seconds on rank 0.
struct ScheduleSummary {
  std::int64_t runs_by_rank0 = 0;     // runs rank 0 computed itself
  std::int64_t runs_by_workers = 0;   // results received from other ranks
  std::int64_t batches_sent = 0;
  std::int64_t bytes_received = 0;
  double wall_s = 0.0;                // the whole schedule, first batch to last result
  double rank0_compute_s = 0.0;       // inside compute() on rank 0
  double rank0_poll_s = 0.0;          // matching, receiving, on_result and answering (every poll, even empty)
  double rank0_tick_s = 0.0;          // inside on_tick (journal flushes, progress)
  double rank0_idle_s = 0.0;          // waiting for results with nothing left to compute
  // Where rank0_poll_s goes (wall): MPI calls (probe, receive, test, send), on_result (every
  // result, its own runs' included) and on_job_done; the rest is bookkeeping and the clock.
  double rank0_mpi_s = 0.0;
  double rank0_result_s = 0.0;
  double rank0_job_output_s = 0.0;
  double rank0_handle_cpu_s = 0.0;    // rank 0's thread CPU time outside compute() until the last result: the per-result work
  double rank0_compute_cpu_s = 0.0;   // rank 0's thread CPU time inside compute()
  std::int64_t jobs_sent = 0;         // side jobs handed to workers
};

using ComputeFn = std::function<void(std::int64_t run_index, std::string& out)>;  // writes one run's bytes
using ResultFn = std::function<void(std::string_view bytes)>;                      // rank 0: one run's bytes
using TickFn = std::function<void()>;                                               // rank 0

// Collective over comm. On rank 0, `todo` lists the runs to compute (ignored elsewhere). Returns
// when every run of `todo` has reached on_result. An exception in compute or on_result aborts the
// job (MPI_Abort): compute is expected to turn run failures into data.
ScheduleSummary run_schedule(MPI_Comm comm, const std::vector<std::int64_t>& todo, const ComputeFn& compute,
                             const ResultFn& on_result, const TickFn& on_tick, const ScheduleOptions& opts = {});

// Completes a request by testing it with sleeps in between (20 us doubling to 1 ms): a rank that
// only waits leaves the core to the others (Open MPI's blocking calls spin, which starves
// oversubscribed hosts).
void wait_idle(MPI_Request* req);

// MPI_Bcast of one int from rank 0, waiting with wait_idle.
int broadcast_int_idle(MPI_Comm comm, int v);

}  // namespace truss::parallel
