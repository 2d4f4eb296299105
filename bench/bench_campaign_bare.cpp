// Benchmark (not a test): the bare simulator on a campaign's runs, for the driver-overhead figure
// of bench/bench_campaign.py. One process, no MPI, no journal, no HDF5:
//   simulate:        sim::simulate on inputs sampled beforehand (the physics alone);
//   sample+simulate: the uniforms, the dispersed scene and mast, then simulate (all a run needs);
//   record path:     the same through append_run_record and a check of its bytes (what a rank
//                    does per run, minus MPI, the journal and the file).
// Usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS]   (default: the campaign's n_runs)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "methods/fixed_design.hpp"
#include "sim/simulate.hpp"

using namespace truss;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS]\n");
    return 2;
  }
  std::vector<std::string> sets;
  if (argc > 2) sets.push_back(std::string("ensemble.n_runs=") + argv[2]);
  const campaign::CampaignContext ctx(campaign::parse_campaign_file(argv[1], sets));
  const methods::FixedDesign design(ctx);
  const methods::RoundPlan plan{0, 0, ctx.options.ensemble.n_runs, {}};
  const auto n = plan.n_runs;
  std::vector<campaign::RunInputs> inputs;
  inputs.reserve(static_cast<std::size_t>(n));
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  const auto t0 = Clock::now();
  for (std::int64_t i = 0; i < n; ++i) {
    design.calc_uniforms(plan, i, u.data());
    inputs.push_back(campaign::calc_run_inputs(ctx.options, ctx.dims, u.data()));
  }
  const auto t1 = Clock::now();
  long ok = 0;
  for (const auto& in : inputs) ok += sim::simulate(in.scene, in.mast).status == sim::RunStatus::ok;
  const auto t2 = Clock::now();
  std::string bytes;
  for (std::int64_t i = 0; i < n; ++i) {
    bytes.clear();
    design.calc_uniforms(plan, i, u.data());
    campaign::append_run_record(ctx, u.data(), {i, 0, 0}, bytes);
    if (!ctx.record.check(bytes).empty()) return 1;
  }
  const auto t3 = Clock::now();
  const double sample_s = std::chrono::duration<double>(t1 - t0).count();
  const double sim_s = std::chrono::duration<double>(t2 - t1).count();
  const double record_s = std::chrono::duration<double>(t3 - t2).count();
  // One line, key=value, for the benchmark script.
  std::printf("runs=%lld ok=%ld sample_s=%.6f simulate_s=%.6f total_s=%.6f record_path_s=%.6f\n",
              static_cast<long long>(n), ok, sample_s, sim_s, sample_s + sim_s, record_s);
  return 0;
}
