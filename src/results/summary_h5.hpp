// The parts of the results file that CampaignFile::write_summary adds once every run is in
// (docs/hdf5-schema.md). Internal to results/.
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "results/campaign_file.hpp"

namespace truss::results {

// /stats: statistics of the ok runs, per float64 output and per bay; status counts. The
// statistics are the streamed ones; a column whose percentiles could not be resolved from the
// kept values and that no rank read back at the end is read back here from the file at `path`
// (this file, read_back.hpp; the same exact order statistics either way). Returns the number of
// columns read back, by the ranks and here.
std::int64_t write_stats(hid_t file, const std::string& path, const campaign::RecordLayout& layout,
                         StreamedStats streamed);
void write_histories(hid_t file, double step_s, const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories);
// Root attributes: what the campaign was, how many runs and rounds, where and when it ran.
void write_root_attributes(hid_t file, const campaign::CampaignContext& ctx, std::int64_t n_runs,
                           const CampaignFileInfo& info);
// /runs/inputs/KEY: the dispersion's distribution as attributes.
void write_input_attributes(hid_t file, const campaign::CampaignOptions& c);
// /timing's per-run datasets are the ResultStore's; the schedule of this session as attributes.
void write_timing_attributes(hid_t file, const ScheduleSummary& s, std::int64_t stats_read_back);

}  // namespace truss::results
