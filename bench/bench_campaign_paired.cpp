// Benchmark (not a test): a run's whole cost inside a 1-rank campaign against the run alone, paired
// run by run so that the VM's speed, which drifts by up to 20 % from one second to the next,
// cancels in the ratio (issue: the campaign's per-run cost within 1.2 x the bare run).
//   alone:  sim::simulate of the run's dispersed scene, made just before, untimed;
//   inside: what a campaign does for that run on one rank, minus MPI: the uniforms, the dispersed
//           scene, the run, the record and its frame (CRC), the owner's check of the frame, the
//           journal, the row into its chunk, and the complete chunks encoded (shuffle, deflate,
//           chunk summaries), placed (H5Dwrite_chunk through the placement driver, statistics
//           merged) and written, one dataset between two runs as the engine does;
//   tail:   the last chunks, /stats, the file closed (once per campaign, reported apart).
// Each run is timed on its own with the steady clock (~40 ns a read, the same for both); which of
// the two goes first alternates run by run. Run on an idle machine; wall times.
// Usage: bench_campaign_paired CAMPAIGN.toml N_RUNS LEVEL DIR
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "methods/fixed_design.hpp"
#include "methods/method_table.hpp"
#include "local_results.hpp"
#include "sim/simulate.hpp"

using namespace truss;

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: bench_campaign_paired CAMPAIGN.toml N_RUNS LEVEL DIR\n");
    return 2;
  }
  mallopt(M_MMAP_THRESHOLD, 64 << 20);  // as truss-campaign does (mpi_driver/truss_campaign.cpp): a chunk's
  mallopt(M_TRIM_THRESHOLD, 256 << 20);  // blocks are reused from the heap, not mapped (and faulted in) anew
  const std::int64_t n = std::atoll(argv[2]);
  const int level = std::atoi(argv[3]);
  const std::string out = std::string(argv[4]) + "/bench_campaign_paired.h5";
  const campaign::CampaignContext ctx(methods::parse_campaign_file(argv[1], {"ensemble.n_runs=" + std::to_string(n)}));
  const methods::FixedDesign design(ctx);
  const methods::RoundPlan plan{0, 0, n, {}};
  bench::LocalResults local(out, ctx, n, level);
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  std::string frame;
  double alone_s = 0, inside_s = 0;
  long sink = 0;
  const auto alone = [&](std::int64_t i) {
    design.calc_uniforms(plan, i, u.data());
    const campaign::RunInputs in = campaign::calc_run_inputs(ctx.options, ctx.dims, u.data());
    const double t0 = now();
    sink += static_cast<long>(sim::simulate(in.scene, in.mast).status);
    alone_s += now() - t0;
  };
  const auto inside = [&](std::int64_t i) {
    const double t0 = now();
    frame.clear();
    design.calc_uniforms(plan, i, u.data());
    const std::size_t start = results::begin_frame(frame);
    campaign::append_run_record(ctx, u.data(), {i, 0, 0}, frame);
    results::seal_frame(frame, start, results::FrameKind::run);
    local.add(frame);
    local.step();
    inside_s += now() - t0;
  };
  for (std::int64_t i = 0; i < n; ++i) {
    if (i % 2 == 0) {
      alone(i);
      inside(i);
    } else {
      inside(i);
      alone(i);
    }
  }
  const double t0 = now();
  local.finish();
  const double tail_s = now() - t0;
  if (sink < 0) return 1;
  std::printf("runs=%lld level=%d alone_us=%.2f inside_us=%.2f ratio=%.4f tail_s=%.3f tail_us_per_run=%.2f\n",
              static_cast<long long>(n), level, 1e6 * alone_s / static_cast<double>(n),
              1e6 * inside_s / static_cast<double>(n), inside_s / alone_s, tail_s,
              1e6 * tail_s / static_cast<double>(n));
  return 0;
}
