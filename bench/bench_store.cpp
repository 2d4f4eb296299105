// Benchmark (not a test): the work a result costs besides its run, and the end, without MPI.
//   per-run cost c:     append_run_record of the campaign's runs (what every rank does per run);
//   per-result cost:    what the owner of its chunk does with each result (the record's frame into
//                       the journal, its row into its chunk, the complete chunks encoded one dataset
//                       at a time between results: shuffle + deflate, chunk summaries, the bytes
//                       written) and, of it, rank 0's part (each chunk placed: H5Dwrite_chunk
//                       through the placement driver, statistics merged), at --compression 0 and 1;
//   tail:               the last chunks, /stats from the streamed statistics, attributes, close,
//                       sync, rename (CampaignFile::write_summary and commit).
// Times are thread CPU time (CLOCK_THREAD_CPUTIME_ID: a shared, loaded machine does not inflate
// them) and wall time; medians of REPEATS. The records are computed once and replayed (cycled
// over the first N_DISTINCT runs, run indices 0..N_RUNS-1) so that N_RUNS can be large.
// Usage: bench_store CAMPAIGN.toml N_RUNS [REPEATS] [N_DISTINCT] [DIR] [--set KEY=VALUE ...]
#include <malloc.h>
#include <time.h>

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
#include "util/bytes.hpp"

using namespace truss;

namespace {

double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Times {
  double h_cpu, h_wall, rank0_cpu, tail_cpu, tail_wall;
};

// One replay of n results into a journal and a results file in dir; the files are removed after.
Times replay(const campaign::CampaignContext& ctx, const std::vector<std::string>& frames, std::int64_t n, int level,
             const std::string& dir) {
  bench::LocalResults local(dir + "/bench_store.h5", ctx, n, level);
  std::string frame;
  const double c0 = cpu_now(), w0 = wall_now();
  for (std::int64_t i = 0; i < n; ++i) {
    frame = frames[static_cast<std::size_t>(i) % frames.size()];
    util::put_at(frame.data() + results::kFrameHeader, i);  // a record starts with its run index
    local.add(frame);
    local.step();
  }
  const double c1 = cpu_now(), w1 = wall_now();
  local.finish();
  const double c2 = cpu_now(), w2 = wall_now();
  const double nd = static_cast<double>(n);
  return {(c1 - c0) / nd, (w1 - w0) / nd, local.rank0_cpu_s / nd, c2 - c1, w2 - w1};
}

}  // namespace

int main(int argc, char** argv) {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);  // as truss-campaign does (mpi_driver/truss_campaign.cpp)
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: bench_store CAMPAIGN.toml N_RUNS [REPEATS] [N_DISTINCT] [DIR] [--set KEY=VALUE ...]\n");
    return 2;
  }
  std::vector<std::string> sets;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--set" && i + 1 < argc) sets.emplace_back(argv[++i]);
    else pos.emplace_back(argv[i]);
  }
  const std::int64_t n = std::atoll(pos[1].c_str());
  const int repeats = pos.size() > 2 ? std::atoi(pos[2].c_str()) : 3;
  const std::int64_t distinct = std::min<std::int64_t>(n, pos.size() > 3 ? std::atoll(pos[3].c_str()) : 2000);
  const std::string dir = pos.size() > 4 ? pos[4] : ".";
  sets.push_back("ensemble.n_runs=" + std::to_string(n));
  const campaign::CampaignContext ctx(methods::parse_campaign_file(pos[0], sets));
  const methods::FixedDesign design(ctx);
  const methods::RoundPlan plan{0, 0, n, {}};
  std::vector<std::string> frames(static_cast<std::size_t>(distinct));
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  const double c0 = cpu_now();
  for (std::int64_t i = 0; i < distinct; ++i) {
    std::string& f = frames[static_cast<std::size_t>(i)];
    design.calc_uniforms(plan, i, u.data());
    const std::size_t start = results::begin_frame(f);
    campaign::append_run_record(ctx, u.data(), {i, 0, 0}, f);
    results::seal_frame(f, start, results::FrameKind::run);
  }
  const double c = (cpu_now() - c0) / static_cast<double>(distinct);
  std::printf("campaign %s, %lld runs (records of %zu bytes, %lld distinct), per-run cost c = %.1f us CPU\n",
              pos[0].c_str(), static_cast<long long>(n), frames[0].size(), static_cast<long long>(distinct), 1e6 * c);
  std::printf("| compression | a result, CPU (us) | wall (us) | / c | of it rank 0's, CPU (us) | / c | tail CPU (s) | "
              "tail wall (s) | tail CPU per 100k runs (s) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const int level : {0, 1}) {
    std::vector<double> hc, hw, r0, tc, tw;
    for (int r = 0; r < repeats; ++r) {
      const Times t = replay(ctx, frames, n, level, dir);
      hc.push_back(t.h_cpu);
      hw.push_back(t.h_wall);
      r0.push_back(t.rank0_cpu);
      tc.push_back(t.tail_cpu);
      tw.push_back(t.tail_wall);
    }
    std::printf("| %d | %.2f | %.2f | %.2f %% | %.3f | %.3f %% | %.3f | %.3f | %.3f |\n", level, 1e6 * median(hc),
                1e6 * median(hw), 100.0 * median(hc) / c, 1e6 * median(r0), 100.0 * median(r0) / c, median(tc),
                median(tw), median(tc) * 1e5 / static_cast<double>(n));
  }
  return 0;
}
