// The campaign results file (kind "campaign", schema in docs/hdf5-schema.md).
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "campaign/result_store.hpp"
#include "campaign/results.hpp"

namespace truss::campaign {

// 2: a Saltelli design draws A and B from the Monte Carlo generator beyond 2d = 8 dimensions
// (kSaltelliSobolMaxDims); 1 drew them from one shifted Sobol' point up to 2d = 2048. Same layout.
inline constexpr std::int64_t kCampaignSchemaVersion = 2;

// How the last session's schedule went (rank 0's view), for /timing: not reproducible.
struct ScheduleTiming {
  double wall_s = 0;            // first batch to last result
  double rank0_compute_s = 0;   // rank 0 inside its own runs
  double rank0_poll_s = 0;      // rank 0 matching, receiving, storing and journalling results, answering
  double rank0_tick_s = 0;      // rank 0 flushing the journal and printing progress
  double rank0_idle_s = 0;      // rank 0 waiting with nothing left to compute (the end)
  std::int64_t runs_by_rank0 = 0, runs_by_workers = 0;
  double synthetic_run_cost_s = -1;  // >= 0: a bench-only campaign of sleeping runs (no physics)
  double rank0_handle_cpu_s = 0;     // rank 0's thread CPU time outside its own runs (results, answers, journal)
  double rank0_compute_cpu_s = 0;    // rank 0's thread CPU time in its own runs
  // Parts of rank0_poll_s (wall): MPI calls; storing results (journal and chunks), of which the
  // journal's share; writing encoded chunks and merging their statistics.
  double rank0_mpi_s = 0, rank0_result_s = 0, rank0_journal_s = 0, rank0_job_output_s = 0;
  // The CPU time of rank 0's write thread (returned chunks written, their statistics merged), not
  // in rank0_handle_cpu_s; 0 without one (one rank, --no-write-thread, an HDF5 that is not thread-safe).
  double rank0_write_thread_cpu_s = 0;
};

struct CampaignFileInfo {
  std::string campaign_toml;     // resolved campaign
  std::string base_scene_toml;   // resolved base scene (single-run format)
  int n_ranks = 1;               // of the invocation that finishes the file
  int n_sessions = 1;            // 1 + resumes
  std::string start_utc, end_utc;
  double wall_time_s = 0.0;      // summed over sessions
  ScheduleTiming schedule;       // of this session
  std::function<void(hid_t file)> write_extra;  // more groups written into the file before it is committed (/nominal)
};

// The results file of a session, written as it runs: created at the start as .NAME.tmp.PID next to
// NAME, the runs streamed into /runs and /timing in run-index chunks (store()), then finish()
// adds the statistics (from the stored columns), the Sobol' indices, the histories and the
// attributes, flushes, closes, syncs and renames it onto NAME (never replacing a file without
// force). HDF5 1.10 files are not crash-safe while open: the journal is what survives a crash,
// and a resumed session writes a new file from it. Destroying an unfinished CampaignFile removes
// its temporary file.
class CampaignFile {
 public:
  CampaignFile(const std::string& path, const CampaignContext& ctx, const StoreOptions& opts);
  ~CampaignFile();
  CampaignFile(const CampaignFile&) = delete;
  CampaignFile& operator=(const CampaignFile&) = delete;
  ResultStore& store() { return *store_; }
  // Starts writing the file's dirty pages to disk without waiting (sync_file_range), so that the
  // final sync in finish() has little left to wait for. Call it now and then: it submits the
  // pages' I/O, milliseconds for a few MB.
  void start_writeback() const;
  // The same as a task, for another thread (the journal's writer) or to run here: it holds its own
  // descriptor of the file (dup), closed when the task is destroyed, run or not. Empty if there is
  // no file.
  std::function<void()> writeback_task() const;
  void finish(const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories, const CampaignFileInfo& info,
              bool force);
  // Removes the .NAME.tmp.PID files that killed sessions left next to `path`, except this
  // process's own; returns their paths. Call while holding the journal's lock (no live session
  // of this campaign can own one then).
  static std::vector<std::string> remove_stale(const std::string& path);
  static std::string temporary_name(const std::string& path);  // .NAME.tmp.PID of this process

 private:
  void discard() noexcept;
  std::string path_, tmp_;
  const CampaignContext& ctx_;
  std::int64_t chunk_rows_;
  hid_t file_ = -1;
  std::unique_ptr<ResultStore> store_;
};

// The end summary's main design values (campaign/progress.hpp) of a finished results file: the
// nominal value, P99.865 and maximum over the ok runs as /stats holds them. Empty if the file
// cannot be read (the summary is a convenience; the file is what counts).
struct DesignValue;
std::vector<DesignValue> read_design_values(const std::string& path, const OutputColumns& cols, const sim::RunResult& nominal);
// "run i: message" of the first run with `status` in a finished results file ("" if none or unreadable).
std::string read_example_message(const std::string& path, std::int64_t n_runs, sim::RunStatus status);

}  // namespace truss::campaign
