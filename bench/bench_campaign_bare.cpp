// Benchmark (not a test): the bare simulator on a campaign's runs, for the driver-overhead figure
// of bench/bench_campaign.py. One process, no MPI, no records, no journal, no HDF5:
//   simulate:       sim::simulate on inputs sampled beforehand (the physics alone);
//   sample+simulate: the uniforms, the dispersed scene and mast, then simulate (all a run needs);
//   record path:     the same through calc_run_record, its bytes and the ResultTable (what rank 0
//                    does per run, minus MPI and the journal).
// Usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS]   (default: the campaign's n_runs)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "campaign/results.hpp"
#include "campaign/run_record.hpp"
#include "sim/simulate.hpp"

using namespace truss;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS]\n");
    return 2;
  }
  campaign::CampaignOptions c = campaign::parse_campaign_file(argv[1]);
  if (argc > 2) c.ensemble.n_runs = std::atoll(argv[2]);
  const campaign::CampaignContext ctx(c);
  const auto n = c.ensemble.n_runs;
  const auto d = static_cast<std::size_t>(ctx.sampler.layout().total);

  std::vector<campaign::RunInputs> inputs;
  inputs.reserve(static_cast<std::size_t>(n));
  std::vector<double> u(d);
  const auto t0 = Clock::now();
  for (std::int64_t i = 0; i < n; ++i) {
    ctx.sampler.calc_uniforms(i, u.data());
    inputs.push_back(campaign::calc_run_inputs(c, ctx.sampler.layout(), u.data()));
  }
  const auto t1 = Clock::now();
  long ok = 0;
  for (const auto& in : inputs) ok += sim::simulate(in.scene, in.mast).status == sim::RunStatus::ok;
  const auto t2 = Clock::now();
  // The driver's per-run path without MPI and journal: record, bytes, back, into the table.
  campaign::ResultTable table(n, ctx.columns);
  std::string bytes;
  for (std::int64_t i = 0; i < n; ++i) {
    bytes.clear();
    campaign::calc_run_record(ctx, i, 0).append_bytes(bytes);
    table.add(campaign::RunRecord::from_bytes(bytes, ctx.columns), 0);
  }
  const auto t3 = Clock::now();
  const double sample_s = std::chrono::duration<double>(t1 - t0).count();
  const double sim_s = std::chrono::duration<double>(t2 - t1).count();
  const double record_s = std::chrono::duration<double>(t3 - t2).count();
  // One line, key=value, for the benchmark script.
  std::printf("runs=%lld ok=%ld sample_s=%.6f simulate_s=%.6f total_s=%.6f record_path_s=%.6f\n", static_cast<long long>(n),
              ok, sample_s, sim_s, sample_s + sim_s, record_s);
  return 0;
}
