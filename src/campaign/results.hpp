// The results of a campaign in memory, in columns (one row per run index), and what rank 0
// computes from them at the end: statistics over the ok runs and, for Saltelli campaigns, Sobol'
// indices per dispersion. Filled from RunRecords in any order; everything computed from it goes
// in run-index order, so it is the same whatever the ranks and the order of completion.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "campaign/run_record.hpp"

namespace truss::campaign {

class ResultTable {
 public:
  ResultTable(std::int64_t n_runs, const OutputColumns& cols);
  void add(const RunRecord& r, int session);  // throws std::runtime_error for a bad or repeated index
  bool has(std::int64_t run) const { return done_[static_cast<std::size_t>(run)] != 0; }
  std::int64_t n_runs() const { return n_; }
  std::int64_t n_done() const { return n_done_; }
  std::int64_t n_failed() const { return n_failed_; }
  const OutputColumns& columns() const { return cols_; }

  // Columns, length n (per-bay and input columns: n x width, row-major).
  std::vector<std::int8_t> status;
  std::vector<std::string> message;
  std::vector<std::vector<double>> f64;          // [column][run]
  std::vector<std::vector<std::int64_t>> i64;    // [column][run]
  std::vector<std::vector<double>> bays;         // [field][run * n_bays_max + bay - 1]
  std::vector<double> inputs;                    // [run * n_inputs + dimension]
  std::vector<double> wall_time_s;
  std::vector<std::int64_t> rank, session;

 private:
  std::int64_t n_;
  OutputColumns cols_;
  std::vector<std::uint8_t> done_;
  std::int64_t n_done_ = 0, n_failed_ = 0;
};

// Percentiles of /stats: 1, 5, 50, 95, 99 and 99.865 (the one-sided 3-sigma level).
inline constexpr std::array<double, 6> kStatPercentiles = {1.0, 5.0, 50.0, 95.0, 99.0, 99.865};
inline constexpr std::array<const char*, 6> kStatPercentileNames = {"p1", "p5", "p50", "p95", "p99", "p99_865"};

struct Stats {
  std::int64_t count = 0;  // values used: finite values of ok runs
  double mean = 0, std = 0, min = 0, max = 0;  // std: sample (ddof = 1); NaN when undefined
  std::array<double, 6> percentiles{};         // kStatPercentiles
};

// Statistics of the finite values among values[i] for which use[i] is true. Percentiles by
// linear interpolation between order statistics (Hyndman-Fan type 7), computed the way
// numpy.percentile does it (index q (n - 1), lerp from the nearer end), so a reader recomputing
// them with numpy gets the same numbers.
Stats calc_stats(const std::vector<double>& values, const std::vector<std::uint8_t>& use);
// The q-th percentile (0..100) of sorted values, as above.
double calc_percentile_sorted(const std::vector<double>& sorted, double q);
// numpy 1.22+ "linear": virtual index h = q/100 (n - 1) between order statistics lo and hi (0-based,
// n > 0); lerp_numpy(a, b, t) = a + t (b - a) for t < 0.5 and b - (1 - t) (b - a) otherwise (exact at
// both ends). The one definition of the interpolation, used by every percentile the tool writes.
struct PercentileIndex {
  std::size_t lo, hi;
  double t;
};
PercentileIndex find_percentile_index(std::size_t n, double q);
double lerp_numpy(double a, double b, double t);

// Sensitivity of one output: Sobol' indices per dispersion from a Saltelli campaign.
struct OutputSensitivity {
  std::string output;
  SobolIndices indices;
  std::int64_t n_blocks = 0, n_blocks_dropped = 0;
};
// Outputs whose sensitivity is computed (the peak loads and the deployment time).
const std::vector<std::string>& sensitivity_outputs();
// Blocks with a failed run or a non-finite output are left out; fewer than 2 usable blocks give
// NaN indices.
std::vector<OutputSensitivity> calc_sensitivity(const ResultTable& t, const CampaignOptions& c);
// Same, from the run statuses and a function that returns a float64 column (all n runs) by name
// (the results file read back, one column at a time).
std::vector<OutputSensitivity> calc_sensitivity(const std::vector<std::int8_t>& status, const OutputColumns& cols,
                                                const CampaignOptions& c,
                                                const std::function<std::vector<double>(const std::string&)>& column);

}  // namespace truss::campaign
