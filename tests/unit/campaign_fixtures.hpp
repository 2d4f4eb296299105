// Shared by the campaign tests: a small campaign (5 bays; per-bay, per-frame and per-run
// dispersions, in that order), and records whose every cell holds a distinct value (value = run +
// cell / 1000, cell = place in the record), so that a value in the wrong row or column shows.
// Every seventh run (run % 7 == 3) is a stall with a message.
#pragma once
#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/evaluate.hpp"
#include "io/scene_toml.hpp"
#include "methods/method_table.hpp"

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
  return methods::parse_campaign_text(text, "small.toml", ".");
}

// The message of the error a campaign text gives ("" if it parses), its source named `name`.
inline std::string campaign_error(const std::string& text, const std::string& name,
                                  const std::vector<std::string>& sets = {}) {
  try {
    methods::parse_campaign_text(text, name, ".", sets);
  } catch (const io::InputError& e) {
    return e.what();
  }
  return {};
}

// A 4-bay base scene with one per-run dispersion (the strut mass, normal 2 %).
inline constexpr const char* kFourBaysStrutMass = R"([scene.mast]
n_bays = 4
[[dispersion]]
key = "mast.strut_mass_kg"
distribution = "normal"
std = 0.02
)";

inline bool stalls(std::int64_t run) { return run % 7 == 3; }
inline double cell_value(std::int64_t run, int cell) { return static_cast<double>(run) + cell / 1000.0; }

// The record of `run`: f64 cells numbered in layout order (cell 0 is the first output's first value).
inline std::string distinct_record(const RecordLayout& L, std::int64_t run, std::int64_t round = 0) {
  std::string out;
  RecordWriter w(L, out);
  w.set_i64(RecordLayout::kRun, run);
  w.set_i64(RecordLayout::kRound, round);
  w.set_i64(RecordLayout::kRank, 1);
  w.set_f64(RecordLayout::kWallTime, 0.5 * static_cast<double>(run));
  w.set_status(stalls(run) ? sim::RunStatus::stall : sim::RunStatus::ok);
  int cell = 0;
  for (std::size_t i = RecordLayout::kWallTime + 1; i < L.fields().size(); ++i) {
    const Field& f = L.fields()[i];
    for (int j = 0; j < f.width; ++j) {
      if (f.type == ValueType::i64) w.set_i64(i, run * 100 + static_cast<std::int64_t>(i), j);
      else w.set_f64(i, cell_value(run, cell++), j);
    }
  }
  w.finish(stalls(run) ? fmt::format("stall: run {}", run) : "");
  return out;
}

}  // namespace truss::campaign::test
