// The campaign results file (kind "campaign", schema in docs/hdf5-schema.md).
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "campaign/evaluate.hpp"
#include "results/result_store.hpp"

namespace truss::results {

// 3: /runs/round, extendible per-run datasets (a method may add rounds of runs), root n_rounds.
// 2: a Saltelli design draws A and B from the Monte Carlo generator beyond 2d = 8 dimensions
// (kSaltelliSobolMaxDims); 1 drew them from one shifted Sobol' point up to 2d = 2048.
inline constexpr std::int64_t kCampaignSchemaVersion = 3;

// How the last session's schedule went (rank 0's view, steady clock and thread CPU seconds), as
// /timing's attributes hold it: not reproducible. The engine fills it; the file writes it as it is.
struct ScheduleSummary {
  double schedule_wall_s = 0;     // first batch handed out to the last chunk written, every round
  double rank0_compute_s = 0;     // rank 0 inside its own runs (their records sent to their owners included)
  double rank0_poll_s = 0;        // looking at and answering messages (batches, the owners' round parts and chunks)
  double rank0_mpi_s = 0;         //   of which inside MPI calls
  double rank0_result_s = 0;      //   of which handling the owners' messages (round parts, placements, statistics)
  double rank0_write_s = 0;       // the chunks rank 0 owns (one rank, restored ones): built, encoded, written
  double rank0_tick_s = 0;        // journal syncs and progress
  double rank0_idle_s = 0;        // waiting with nothing to compute or write (ends of rounds)
  double rank0_handle_cpu_s = 0;  // rank 0's thread CPU time outside its own runs (all of the above)
  double rank0_compute_cpu_s = 0;  // rank 0's thread CPU time inside its own runs
  std::int64_t runs_by_rank0 = 0, runs_by_workers = 0;
  int statistics_ranks = 1;        // the ranks that merged the statistics, each a range of the columns
  double stats_merge_cpu_s = 0;    // the largest of their thread CPU times merging
  int stats_read_back_ranks = 0;   // ranks that read statistics columns back at the end (read_back.hpp)
  double synthetic_run_cost_s = -1;  // >= 0: a bench-only campaign of sleeping runs (no physics)
};

struct CampaignFileInfo {
  std::string campaign_toml;    // resolved campaign
  std::string base_scene_toml;  // resolved base scene (single-run format)
  std::string motor_declared_by;  // campaign/motor_declared.hpp: "" when the campaign declares no motor
  int n_ranks = 1;              // of the invocation that finishes the file
  int n_sessions = 1;           // 1 + resumes
  std::int64_t n_rounds = 1;    // rounds of runs the method ran
  std::string start_utc, end_utc;
  double wall_time_s = 0.0;     // summed over sessions
  ScheduleSummary schedule;     // of this session
};

// The results file of a session, written as it runs: created at the start as .NAME.tmp.PID next to
// NAME (through the placement driver), the runs' chunks placed in /runs and /timing as the ranks
// that built them report them (store()) and written there by those ranks; write_summary()
// adds the statistics, the histories, /nominal and the attributes, a method may add its own groups
// (handle()), and commit() flushes, closes, syncs and renames it onto NAME (never replacing a file
// without force). HDF5 1.10 files are not crash-safe while open: the journal is what survives a
// crash, and a resumed session writes a new file from it. Destroying an uncommitted CampaignFile
// removes its temporary file.
class CampaignFile {
 public:
  CampaignFile(const std::string& path, const campaign::CampaignContext& ctx, const StoreOptions& opts);
  ~CampaignFile();
  CampaignFile(const CampaignFile&) = delete;
  CampaignFile& operator=(const CampaignFile&) = delete;
  ResultStore& store() { return *store_; }
  // The temporary file being written (.NAME.tmp.PID of rank 0): the ranks write the chunks they
  // built into it at the addresses the store placed them at.
  const std::string& temporary_path() const { return tmp_; }
  // Every run in: the last chunks written, /stats (from the streamed statistics of the statistics
  // rank, chunk_stats.hpp), /histories, /nominal and the attributes.
  void write_summary(StreamedStats streamed, const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories,
                     const sim::RunResult& nominal, const CampaignFileInfo& info);
  hid_t handle() const { return file_; }
  void commit(bool force);
  // A fatal error, the job about to be aborted (no destructor will run): the temporary file
  // removed now, without closing it (the library may have failed inside it).
  void remove_temporary() noexcept;
  // Removes the .NAME.tmp.PID files that killed sessions left next to `path`, except this
  // process's own; returns their paths. Call while holding the output's lock (lock_name: no live
  // session of this campaign can own one then).
  static std::vector<std::string> remove_stale(const std::string& path);
  static std::string temporary_name(const std::string& path);  // .NAME.tmp.PID of this process
  // .NAME.lock: the lock (results/lock_file.hpp) a campaign holds on its output from before any check
  // of its journal and temporary files until its journal is removed.
  static std::string lock_name(const std::string& path);

 private:
  void discard() noexcept;
  std::string path_, tmp_;
  const campaign::CampaignContext& ctx_;
  PlacementState placement_;  // before file_: the driver refers to it while the file is open
  hid_t file_ = -1;
  std::unique_ptr<ResultStore> store_;
};

// /nominal: the base scene's run as a row of /runs would hold it, with its per-bay values (n_bays_max
// of them) and its history.
void write_nominal_group(hid_t file, const sim::RunResult& r, int n_bays_max);

// The end summary's main design values of a finished results file: each shown output's nominal
// value, P99.865 and maximum over `count` ok runs with a finite value, as /stats holds them. Empty
// if the file cannot be read (the summary is a convenience; the file is what counts).
struct DesignValue {
  std::string label, units;
  double nominal, p99_865, max;
  std::int64_t count = 0;
};
std::vector<DesignValue> read_design_values(const std::string& path, const campaign::RecordLayout& layout,
                                            const sim::RunResult& nominal);
// "run i: message" of the first run with `status` in a finished results file ("" if none or unreadable).
std::string read_example_message(const std::string& path, std::int64_t n_runs, sim::RunStatus status);

}  // namespace truss::results
