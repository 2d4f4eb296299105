// Shared by the campaign tests: a small campaign (5 bays; per-bay, per-frame and per-run
// dispersions, in that order), and records whose every cell holds a distinct value (value = run +
// cell / 1000, cell = place in the record), so that a value in the wrong row or column shows.
#pragma once
#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/run_record.hpp"

namespace truss::campaign::test {

inline CampaignOptions small_campaign(const std::string& sampling = "latin_hypercube", std::int64_t n_runs = 24) {
  const std::string text = fmt::format(R"(
[ensemble]
n_runs = {}
master_seed = 11
sampling = "{}"
[scene.mast]
n_bays = 5
[[dispersion]]
key = "mast.strut_mass_kg"
per = "bay"
distribution = "normal"
std = 0.02
[[dispersion]]
key = "mast.frame_side_m"
per = "frame"
apply = "offset"
distribution = "uniform"
lower = -0.0005
upper = 0.0005
[[dispersion]]
key = "drive.speed_m_per_s"
apply = "relative"
distribution = "uniform"
lower = -0.1
upper = 0.1
)", n_runs, sampling);
  return parse_campaign_text(text, "small.toml", ".");
}

inline RunRecord distinct_record(const OutputColumns& cols, std::int64_t run) {
  RunRecord r;
  r.run_index = run;
  r.rank = 1;
  double cell = 0;
  auto v = [&] { return static_cast<double>(run) + (cell++) / 1000.0; };
  for (std::size_t k = 0; k < cols.f64.size(); ++k) r.f64.push_back(v());
  for (std::size_t k = 0; k < cols.i64.size(); ++k) r.i64.push_back(run * 100 + static_cast<std::int64_t>(k));
  for (std::size_t k = 0; k < cols.bay.size() * static_cast<std::size_t>(cols.n_bays_max); ++k) r.bays.push_back(v());
  for (int k = 0; k < cols.n_inputs; ++k) r.inputs.push_back(v());
  return r;
}

}  // namespace truss::campaign::test
