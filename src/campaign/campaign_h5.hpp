// The campaign results file (kind "campaign", schema in docs/hdf5-schema.md), written once at the
// end from the in-memory table, atomically: to .NAME.tmp.PID, synced, then renamed onto NAME
// (never replacing an existing file without force).
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "campaign/results.hpp"

namespace truss::campaign {

inline constexpr std::int64_t kCampaignSchemaVersion = 1;

// How the last session's schedule went (rank 0's view), for /timing: not reproducible.
struct ScheduleTiming {
  double wall_s = 0;            // first batch to last result
  double rank0_compute_s = 0;   // rank 0 inside its own runs
  double rank0_poll_s = 0;      // rank 0 matching, receiving, storing and journalling results, answering
  double rank0_tick_s = 0;      // rank 0 flushing the journal and printing progress
  double rank0_idle_s = 0;      // rank 0 waiting with nothing left to compute (the end)
  std::int64_t runs_by_rank0 = 0, runs_by_workers = 0;
  double synthetic_run_cost_s = -1;  // >= 0: a bench-only campaign of sleeping runs (no physics)
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

void write_campaign_h5(const std::string& path, const CampaignContext& ctx, const ResultTable& table,
                       const std::vector<OutputSensitivity>& sensitivity,
                       const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories,
                       const CampaignFileInfo& info, bool force);

}  // namespace truss::campaign
