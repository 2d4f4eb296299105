// Benchmark (not a test): the bare simulator on a campaign's runs, and what a rank adds to each run,
// for the driver-overhead figures of bench/bench_campaign.py and docs/benchmarks.md. One process,
// no MPI, no journal, no HDF5. Times per pass over the runs (each pass over every run in turn):
//   uniforms:        the method's uniforms of each run (Latin hypercube, Sobol', ...);
//   inputs:          the dispersed scene and mast from them (calc_run_inputs);
//   simulate:        sim::simulate on inputs made beforehand (the physics alone: the bare run);
//   encode:          append_record of results computed beforehand (the record's bytes alone);
//   record path:     calc_uniforms + append_run_record, the record's bytes checked (what a rank
//                    does per run, minus MPI, the journal and the file).
// The passes are interleaved REPEATS times (default 3) and each time is the median of its passes.
// Times are the thread's CPU time (CLOCK_THREAD_CPUTIME_ID): on a shared machine the time the
// process waits for a core does not count.
// Usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS [REPEATS]]   (default: the campaign's n_runs)
#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "methods/fixed_design.hpp"
#include "methods/method_table.hpp"
#include "sim/simulate.hpp"

using namespace truss;

namespace {
struct Clock {
  static double now() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  }
};
double seconds_since(double t0) { return Clock::now() - t0; }
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_campaign_bare CAMPAIGN.toml [N_RUNS [REPEATS]]\n");
    return 2;
  }
  std::vector<std::string> sets;
  if (argc > 2) sets.push_back(std::string("ensemble.n_runs=") + argv[2]);
  const int repeats = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  const campaign::CampaignContext ctx(methods::parse_campaign_file(argv[1], sets));
  const methods::FixedDesign design(ctx);
  const methods::RoundPlan plan{0, 0, ctx.options.ensemble.n_runs, {}};
  const auto n = plan.n_runs;
  const auto un = static_cast<std::size_t>(n);
  const auto dims = static_cast<std::size_t>(ctx.dims.total);
  std::vector<double> u(un * dims);
  std::vector<campaign::RunInputs> inputs(un);
  std::vector<sim::RunResult> results(un);
  std::vector<double> t_uniforms, t_inputs, t_simulate, t_encode, t_record;
  long ok = 0;
  std::string bytes;
  for (int rep = 0; rep < repeats; ++rep) {
    auto t0 = Clock::now();
    for (std::size_t i = 0; i < un; ++i) design.calc_uniforms(plan, static_cast<std::int64_t>(i), &u[i * dims]);
    t_uniforms.push_back(seconds_since(t0));
    t0 = Clock::now();
    for (std::size_t i = 0; i < un; ++i) inputs[i] = campaign::calc_run_inputs(ctx.options, ctx.dims, &u[i * dims]);
    t_inputs.push_back(seconds_since(t0));
    t0 = Clock::now();
    for (std::size_t i = 0; i < un; ++i) results[i] = sim::simulate(inputs[i].scene, inputs[i].mast);
    t_simulate.push_back(seconds_since(t0));
    ok = std::count_if(results.begin(), results.end(), [](const auto& r) { return r.status == sim::RunStatus::ok; });
    t0 = Clock::now();
    std::vector<double> values(dims);
    for (std::size_t i = 0; i < un; ++i) {
      bytes.clear();
      campaign::append_record(ctx.record, {static_cast<std::int64_t>(i), 0, 0}, results[i], values, bytes);
    }
    t_encode.push_back(seconds_since(t0));
    t0 = Clock::now();
    for (std::int64_t i = 0; i < n; ++i) {
      bytes.clear();
      design.calc_uniforms(plan, i, u.data());
      campaign::append_run_record(ctx, u.data(), {i, 0, 0}, bytes);
      if (!ctx.record.check(bytes).empty()) return 1;
    }
    t_record.push_back(seconds_since(t0));
  }
  const double sample_s = median(t_uniforms) + median(t_inputs), sim_s = median(t_simulate);
  // One line, key=value, for the benchmark script (sample_s = uniforms_s + inputs_s).
  std::printf("runs=%lld ok=%ld uniforms_s=%.6f inputs_s=%.6f sample_s=%.6f simulate_s=%.6f encode_s=%.6f "
              "total_s=%.6f record_path_s=%.6f\n",
              static_cast<long long>(n), ok, median(t_uniforms), median(t_inputs), sample_s, sim_s,
              median(t_encode), sample_s + sim_s, median(t_record));
  return 0;
}
