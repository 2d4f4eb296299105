// Benchmark (not a test): the merge of chunk summaries into a column's streamed statistics
// (ColumnStats::add, sampling/column_stats.hpp). A normal column of N values in chunks of 4,096;
// each summary is made when its chunk is written (against the windows of that moment) and merged
// LAG chunks later (0: at once, as rank 0 does). Only the merges are timed (steady clock); median
// over REPEATS of the mean per merge.
//   bench_column_stats [N=100000] [REPEATS=200] [LAG=0]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <random>
#include <vector>

#include "sampling/column_stats.hpp"

using namespace truss::sampling;

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 100000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 200;
  const std::size_t lag = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 0;
  const std::size_t rows = 4096, n_chunks = (n + rows - 1) / rows;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(1.0, 0.1);
  std::vector<double> v(n);
  const std::vector<std::uint8_t> use(n, 1);
  std::vector<double> per_merge_us;
  std::size_t kept = 0;
  for (int rep = 0; rep < repeats; ++rep) {
    for (double& x : v) x = g(rng);
    ColumnStats cs;
    std::deque<std::pair<std::size_t, ChunkSummary>> in_flight;
    const char* bytes = reinterpret_cast<const char*>(v.data());
    double merge_s = 0.0;
    for (std::size_t c = 0; c < n_chunks; ++c) {
      const std::size_t r = std::min(rows, n - c * rows);
      if (!cs.seeded()) cs.seed(bytes, r, 1, use.data());
      in_flight.emplace_back(c, calc_chunk_summary(bytes + 8 * rows * c, r, 1, use.data(), cs.windows()));
      while (in_flight.size() > lag || (c + 1 == n_chunks && !in_flight.empty())) {
        const auto t0 = std::chrono::steady_clock::now();
        cs.add(static_cast<std::int64_t>(in_flight.front().first), std::move(in_flight.front().second));
        merge_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        in_flight.pop_front();
      }
    }
    bool resolved = false;
    if (cs.calc_stats(resolved).count != static_cast<std::int64_t>(n) || !resolved) return 1;
    kept = cs.kept_values();
    per_merge_us.push_back(merge_s / static_cast<double>(n_chunks) * 1e6);
  }
  std::sort(per_merge_us.begin(), per_merge_us.end());
  const double med = per_merge_us[per_merge_us.size() / 2];
  std::printf("%zu values, chunks of %zu, merged %zu chunks late, %d repeats: %.2f us a chunk's merge (median), "
              "%.3f ns a value of the column; %zu values kept at the end\n",
              n, rows, lag, repeats, med, med * 1e3 * static_cast<double>(n_chunks) / static_cast<double>(n), kept);
  return 0;
}
