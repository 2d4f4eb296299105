// Rank 0's results of a running campaign, streamed into the open results file in run-index
// chunks. Runs arrive in any order; a chunk's rows are held until every one of its runs has
// arrived, then written to /runs and /timing and the chunk's memory is reused. Runs are handed out
// in index order, so only the chunks around the scheduling front are in memory: rank 0's memory
// is (chunks in flight) x (chunk rows) x (record size) plus one byte per run, not n x 4.5 kB.
// What is written does not depend on the order of arrival, so the file holds the same values on
// any number of ranks and after --resume.
#pragma once
#include <array>
#include <atomic>
#include <hdf5.h>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/buffer_pool.hpp"
#include "campaign/task_thread.hpp"
#include "campaign/results.hpp"
#include "campaign/run_record.hpp"
#include "io/h5_util.hpp"

namespace truss::campaign {

// How the per-run datasets are stored.
struct StoreOptions {
  std::int64_t chunk_runs = 4096;  // rows per chunk: 32 kB per float64 column, a few chunks in memory
  int deflate_level = 1;           // zlib level (0: no compression); 1: the fastest, most of level 9's ratio
  bool offload_encoding = false;   // jobs wait for take_job (other ranks encode them), up to two chunks' bytes
  std::size_t job_headroom_bytes = 1024;  // spare room after each job for what carries it (a work message: 8 bytes a run)
  // Records copied into the chunks, chunks completed, encoded chunks that come back (job_done with
  // an owner) written and their statistics merged on a thread of their own, not by the thread that
  // answers the workers (only with a thread-safe HDF5).
  bool write_thread = false;
  std::string validate() const;
};

// Rows per chunk for a campaign of n runs: 4,096 (32 kB a float64 column) from 65,536 runs up;
// smaller campaigns get at least 16 chunks (at least 512 rows), so that encoding and summarising
// the chunks overlaps the runs instead of all falling on the end with the last chunk. A function
// of n alone: the file is the same on any number of ranks and after --resume.
inline std::int64_t find_chunk_runs(std::int64_t n_runs) { return n_runs / 16 < 512 ? 512 : n_runs / 16 > 4096 ? 4096 : n_runs / 16; }

// The statistics of the output columns from the chunks' summaries (column_stats.hpp): per float64
// column and per bay of each per-bay field. `resolved` 0: a percentile's order statistics were not
// kept (its percentiles are NaN), compute them from the stored column.
struct StreamedStats {
  std::vector<Stats> f64;
  std::vector<std::uint8_t> f64_resolved;
  std::vector<std::vector<Stats>> bays;  // [field][bay - 1]
  std::vector<std::vector<std::uint8_t>> bays_resolved;
  std::size_t kept_values = 0;  // values held for the percentiles, all columns
};

// Encoding a completed chunk (shuffle + deflate, about 60 us of zlib per 4.4 kB record at level
// 1) is the only heavy part of storing a result. It is packaged as jobs, one per dataset chunk
// (encode_job_output is a pure function of the job's bytes): the scheduler hands them to workers
// with their next batch and the encoded bytes come back with the batch's results (take_job,
// job_done), so rank 0 only copies values and writes finished chunks with H5Dwrite_chunk (both on
// its write thread, StoreOptions::write_thread, with the statistics merge: the thread that answers
// the workers only checks and counts each record). Jobs
// that nobody takes (one rank, the end of the schedule, a backlog beyond two chunks) are encoded
// on rank 0 (drain_jobs). The bytes are the same whoever encodes them.
class ResultStore {
 public:
  // Creates /runs (and its bays, inputs groups) and /timing's per-run datasets in `file`, chunked
  // by chunk_runs rows, shuffled and deflated unless deflate_level is 0.
  ResultStore(hid_t file, const CampaignContext& ctx, const StoreOptions& opts);
  ~ResultStore();
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;

  // A record's bytes (RunRecord::append_bytes), checked and counted here. They go into the chunk
  // buffers here, or, with a write thread, are staged (copied) and put in on that thread. Throws
  // std::runtime_error for a bad or repeated index or bytes that are not a record of these columns.
  void add_bytes(std::string_view record, int session);
  void add(const RunRecord& r, int session);
  // Records inside `owner` (a worker's message): each view from byte `skip` on is a record. Checked
  // and counted here, as add_bytes; put into the chunk buffers on the write thread, which keeps
  // `owner` until then (without one: here, before returning).
  void add_records(std::shared_ptr<const char[]> owner, const std::vector<std::string_view>& views, std::size_t skip,
                   int session);
  // True while encoding jobs may still appear (records handed to the write thread and not yet in
  // their chunks: staged ones are handed over now) or wait to be taken. The schedule does not end
  // while it says so: the last chunk's jobs still go to the workers.
  bool jobs_pending();
  bool has(std::int64_t run) const { return done_[static_cast<std::size_t>(run)] != 0; }
  std::int64_t n_runs() const { return n_; }
  std::int64_t n_done() const { return n_done_; }
  std::int64_t n_failed() const { return n_failed_; }
  // Runs per RunStatus value so far (restored and new), for progress lines by status name.
  const std::array<std::int64_t, sim::kRunStatusCount>& status_counts() const { return status_counts_; }
  std::int64_t chunk_runs() const { return chunk_; }
  std::size_t peak_chunks_in_memory() const { return peak_chunks_; }  // (after finish_writes)

  // Encoding jobs: take_job moves the next one into `job` (false when none is waiting);
  // job_done writes an encoded chunk (encode_job_output of a job); drain_jobs encodes and writes
  // every job still waiting. Counters for the end summary.
  bool take_job(std::string& job);
  void job_done(std::string_view output);
  // The same for an output inside the owner_bytes that `owner` keeps alive (what the write thread
  // holds until it has written the output, counted against its limit): on the write thread if any.
  void job_done(std::shared_ptr<const char[]> owner, std::size_t owner_bytes, std::string_view output);
  // Hands over the staged records and waits until the write thread has done everything handed to
  // it; rethrows its error.
  void finish_writes();
  bool has_write_thread() const { return writes_ != nullptr; }
  double calc_write_thread_cpu_s() const;  // 0 without a write thread
  void drain_jobs();
  bool drain_one();  // encodes and writes the next waiting job here; false if none
  // A job's buffer back once it has been sent: the next chunks reuse its memory (no page faults,
  // no zeroing of 18 MB a chunk). Kept up to two chunks' bytes; beyond that it is freed.
  void recycle(std::string&& buffer);
  std::int64_t jobs_offloaded() const { return jobs_returned_; }
  std::int64_t jobs_local() const { return jobs_local_.load(); }
  // Throws std::runtime_error unless every run has arrived and every chunk is written (after
  // finish_writes).
  void check_complete();
  // The output columns' statistics over the ok runs of the chunks written so far (after finish_writes).
  StreamedStats calc_stats();

 private:
  struct Chunk;
  struct Datasets;
  struct Tracking;
  std::uint64_t append_request(std::string& part, std::size_t j, const std::vector<std::uint8_t>& use);
  void accept(std::string_view rec);                   // checks and counts a record (rank 0's thread)
  void store_record(std::string_view rec, int session);  // puts it into its chunk (the write thread, if any)
  void post_staged();
  Chunk& chunk_for(std::int64_t run);
  void complete_chunk(Chunk& c);
  bool over_backlog();
  bool pop_job(std::string& job);  // the next waiting job, under jobs_m_ (false: none)
  void write_encoded(std::string_view output);
  void attach_scales(hid_t file, Datasets& d);

  const CampaignContext& ctx_;
  std::int64_t n_, chunk_;
  int deflate_;
  std::vector<std::uint8_t> done_;
  std::int64_t n_done_ = 0, n_failed_ = 0;
  std::array<std::int64_t, sim::kRunStatusCount> status_counts_{};
  std::map<std::int64_t, std::unique_ptr<Chunk>> open_;  // by chunk index
  std::vector<std::unique_ptr<Chunk>> spare_;              // written chunks, memory kept for reuse
  std::size_t peak_chunks_ = 0;
  std::unique_ptr<Datasets> ds_;
  std::unique_ptr<Tracking> track_;
  // Made where chunks complete (the write thread, if any), taken and recycled by rank 0's thread:
  std::mutex jobs_m_;             // jobs_, jobs_bytes_ and pool_
  std::deque<std::string> jobs_;  // waiting encoding jobs
  std::size_t jobs_bytes_ = 0, max_jobs_bytes_ = 0;
  std::size_t headroom_ = 0;
  BufferPool pool_;  // buffers of sent and encoded jobs, for the next chunks
  std::int64_t jobs_out_ = 0, jobs_returned_ = 0;
  std::atomic<std::int64_t> jobs_local_{0};  // drain_one runs on either thread
  // Records for the write thread: copies of the ones add_bytes gets (u32 length, i32 session,
  // bytes), handed over in groups; and how many were handed over and how many are in their chunks.
  std::string staged_;
  std::int64_t staged_n_ = 0;
  std::int64_t records_posted_ = 0;
  std::atomic<std::int64_t> records_stored_{0};
  std::mutex stats_m_;                 // track_: seeded and read here, merged on the write thread
  std::unique_ptr<TaskThread> writes_;  // last: stopped first
};

// What a worker does with an encoding job: the job's chunk encoded (encode_chunk), framed so that
// job_done knows where it goes.
void encode_job_output(std::string_view job, std::string& out);

// Reading the finished /runs back (statistics, sensitivity): a 1-D float64 column; columns
// col0 .. col0 + cols - 1 of an n x width dataset, read in blocks of block_rows whole rows (whole
// chunks: each is decompressed once per call).
std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n);
std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n, std::int64_t width,
                                                  std::int64_t col0, std::int64_t cols, std::int64_t block_rows);
std::vector<std::int8_t> read_status(hid_t file, std::int64_t n);
// The message of one run (/runs/message[run]).
std::string read_message(hid_t file, std::int64_t run);

}  // namespace truss::campaign
