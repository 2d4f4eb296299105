// One campaign run, from its index to a compact record: the run's uniforms (RunSampler), its
// dispersed scene and mast (calc_run_inputs), the simulation, and the outputs the campaign file
// stores (OutputColumns), packed into bytes that travel over MPI and into the journal unchanged.
// A record depends on (campaign, run index) only; `rank` and `wall_time_s` are the only fields that
// depend on where and when it ran.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/campaign.hpp"
#include "campaign/dispersion.hpp"
#include "campaign/sampling.hpp"
#include "io/json_summary.hpp"
#include "sim/result.hpp"

namespace truss::campaign {

// The uniforms of run i: the campaign's SamplePlan over all dimensions. saltelli: the plan's
// factor groups are the dispersions (blocks of G + 2 runs A, B, AB_1 .. AB_G), so AB_g takes every
// dimension of dispersion g (all its bays) from B; the base points are shifted Sobol' points of
// dimension 2d up to 2d = kSaltelliSobolMaxDims, Monte Carlo points beyond, see SamplePlan.
class RunSampler {
 public:
  explicit RunSampler(const CampaignOptions& c);
  const DimensionLayout& layout() const { return layout_; }
  void calc_uniforms(std::int64_t run_index, double* u) const;  // u[layout().total]
 private:
  DimensionLayout layout_;
  SamplePlan plan_;
};

// Which outputs a record holds: the numeric scalar fields of RunResult (wall_time_s apart: it
// is not reproducible and travels separately) and the per-bay fields of BayResult (bay apart).
struct OutputColumns {
  std::vector<const io::RunField*> f64;
  std::vector<const io::RunField*> i64;
  std::vector<const io::BayField*> bay;
  int n_bays_max = 0;
  int n_inputs = 0;  // layout.total: the applied values of every dispersion dimension
  static OutputColumns make(const DimensionLayout& layout);
};

struct RunRecord {
  std::int64_t run_index = -1;
  sim::RunStatus status = sim::RunStatus::ok;
  std::string message;
  std::vector<double> f64;         // OutputColumns::f64 order
  std::vector<std::int64_t> i64;   // OutputColumns::i64 order
  std::vector<double> bays;        // [field * n_bays_max + bay - 1], NaN where not reached
  std::vector<double> inputs;      // [layout dimension], NaN beyond the run's bay count
  double wall_time_s = 0.0;        // simulation wall time (not reproducible)
  std::int32_t rank = 0;           // rank that computed it (not reproducible)

  // Little-endian byte image (this project runs on little-endian machines only; checked at build).
  void append_bytes(std::string& out) const;
  // Throws std::runtime_error if the bytes do not hold a record of these columns.
  static RunRecord from_bytes(std::string_view bytes, const OutputColumns& cols);
};

struct CampaignContext {
  CampaignOptions options;
  RunSampler sampler;
  OutputColumns columns;
  explicit CampaignContext(CampaignOptions c);
};

// Samples, disperses and simulates run `run_index` with the campaign's wall-time cap. Never throws
// for a failed run: the failure is the record's status and message.
RunRecord calc_run_record(const CampaignContext& ctx, std::int64_t run_index, int rank);

// The dispersed scene of a run with time histories every step_s: for [output] history_runs.
sim::RunResult calc_run_with_history(const CampaignContext& ctx, std::int64_t run_index, double step_s);

}  // namespace truss::campaign
