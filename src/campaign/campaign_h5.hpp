// The campaign results file (kind "campaign", schema in docs/hdf5-schema.md), written once at the
// end from the in-memory table, atomically: to .NAME.tmp.PID, synced, then renamed onto NAME
// (never replacing an existing file without force).
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "campaign/results.hpp"

namespace truss::campaign {

inline constexpr std::int64_t kCampaignSchemaVersion = 1;

struct CampaignFileInfo {
  std::string campaign_toml;     // resolved campaign
  std::string base_scene_toml;   // resolved base scene (single-run format)
  int n_ranks = 1;               // of the invocation that finishes the file
  int n_sessions = 1;            // 1 + resumes
  std::string start_utc, end_utc;
  double wall_time_s = 0.0;      // summed over sessions
};

void write_campaign_h5(const std::string& path, const CampaignContext& ctx, const ResultTable& table,
                       const std::vector<OutputSensitivity>& sensitivity,
                       const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories,
                       const CampaignFileInfo& info, bool force);

}  // namespace truss::campaign
