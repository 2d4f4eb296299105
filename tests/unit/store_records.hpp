// Shared by the result-store tests: a small campaign with a per-bay and a per-run dispersion, and
// records whose every cell holds a distinct value (value = run + cell / 1000, cell = place in the
// record), so that a value in the wrong row or column shows.
#pragma once
#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/run_record.hpp"

namespace truss::campaign::test {

inline std::string store_campaign_text(std::int64_t n_runs) {
  return fmt::format(R"(
[ensemble]
n_runs = {}
master_seed = 5
[scene.mast]
n_bays = 4
[[dispersion]]
key = "mast.strut_mass_kg"
per = "bay"
distribution = "normal"
std = 0.02
[[dispersion]]
key = "drive.speed_m_per_s"
apply = "relative"
distribution = "uniform"
lower = -0.1
upper = 0.1
)",
                     n_runs);
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
