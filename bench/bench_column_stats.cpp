// Benchmark (not a test): a column's streamed statistics (statistics/column_stats.hpp) as rank 0
// pays them: the first windows (ColumnStats::seed), each chunk's summary (calc_chunk_summary, as
// the chunk is written) and its merge (ColumnStats::add). A normal column of N values in chunks of
// 4,096; each summary is made against the windows of its moment and merged LAG chunks later (0: at
// once, as rank 0 does); a merged summary's room is used again for the next, as rank 0 does. Each
// part is timed apart (steady clock); medians over REPEATS of the cost per value of the column (the
// seed: per column).
//   bench_column_stats [N=100000] [REPEATS=200] [LAG=0]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <random>
#include <vector>

#include "statistics/column_stats.hpp"

using namespace truss::statistics;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 100000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 200;
  const std::size_t lag = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 0;
  const std::size_t rows = 4096, n_chunks = (n + rows - 1) / rows;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(1.0, 0.1);
  std::vector<double> v(n);
  const std::vector<std::uint8_t> use(n, 1);
  std::vector<double> seed_us, summary_ns, merge_ns;
  std::size_t kept = 0;
  for (int rep = 0; rep < repeats; ++rep) {
    for (double& x : v) x = g(rng);
    ColumnStats cs;
    std::deque<std::pair<std::size_t, ChunkSummary>> in_flight;
    std::vector<ChunkSummary> spare;
    const char* bytes = reinterpret_cast<const char*>(v.data());
    double seed_s = 0.0, summary_s = 0.0, merge_s = 0.0;
    for (std::size_t c = 0; c < n_chunks; ++c) {
      const std::size_t r = std::min(rows, n - c * rows);
      auto t0 = std::chrono::steady_clock::now();
      if (!cs.seeded()) {
        cs.seed(bytes, r, 1, use.data());
        seed_s += seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
      }
      in_flight.emplace_back(c, ChunkSummary{});
      if (!spare.empty()) {  // a merged summary's room, used again as the store does
        in_flight.back().second = std::move(spare.back());
        spare.pop_back();
      }
      calc_chunk_summary(bytes + 8 * rows * c, r, 1, use.data(), cs.windows(), in_flight.back().second);
      summary_s += seconds_since(t0);
      while (in_flight.size() > lag || (c + 1 == n_chunks && !in_flight.empty())) {
        t0 = std::chrono::steady_clock::now();
        cs.add(static_cast<std::int64_t>(in_flight.front().first), in_flight.front().second);
        merge_s += seconds_since(t0);
        spare.push_back(std::move(in_flight.front().second));
        in_flight.pop_front();
      }
    }
    bool resolved = false;
    if (cs.calc_stats(resolved).count != static_cast<std::int64_t>(n) || !resolved) return 1;
    kept = cs.kept_values();
    seed_us.push_back(seed_s * 1e6);
    summary_ns.push_back(summary_s * 1e9 / static_cast<double>(n));
    merge_ns.push_back(merge_s * 1e9 / static_cast<double>(n));
  }
  std::printf("%zu values, chunks of %zu, merged %zu chunks late, %d repeats (medians): seed %.1f us a "
              "column, summaries %.3f ns a value, merges %.3f ns a value; %zu values kept at the end\n",
              n, rows, lag, repeats, median(seed_us), median(summary_ns), median(merge_ns),
              kept);
  return 0;
}
