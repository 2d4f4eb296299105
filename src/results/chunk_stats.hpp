// The statistics of the output columns, merged from the chunks' summaries on the statistics ranks
// (engine.hpp), each a range of the columns: each column's ColumnStats
// (statistics/column_stats.hpp), the windows the owners summarise their chunks against, and at the
// end the streamed statistics that rank 0 writes to /stats. Its work is per chunk summary, never
// per run; the result is a function of the chunks' values alone (the windows only decide what is
// kept): the same on any number of ranks, whichever ranks merge, and after --resume.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/record.hpp"
#include "results/chunk_builder.hpp"
#include "statistics/column_stats.hpp"
#include "statistics/stats.hpp"

namespace truss::results {

// The statistics of the output columns: per float64 output and per bay of each per-bay output, in
// RecordLayout order. `resolved` 0: a percentile's order statistics were not kept (its percentiles
// are NaN): compute them from the stored column.
struct StreamedStats {
  std::vector<statistics::Stats> f64;
  std::vector<std::uint8_t> f64_resolved;
  std::vector<std::vector<statistics::Stats>> bays;  // [field][bay - 1]
  std::vector<std::vector<std::uint8_t>> bays_resolved;
  std::size_t kept_values = 0;  // values held for the percentiles, all columns
  std::int64_t read_back = 0;   // columns resolved from the stored file (read_back.hpp)
};

// Where the statistics columns are merged: `count` statistics ranks first .. first + count - 1,
// rank first + s merging the contiguous columns find_columns(first + s, n_stats), sizes within one.
// The merge's cost is per chunk and column, so S ranks share it S ways (docs/architecture.md).
struct StatsRanks {
  int first = 0;
  int count = 1;
  bool holds(int rank) const { return rank >= first && rank < first + count; }
  ColumnRange find_columns(int rank, std::size_t n_stats) const {
    const auto s = static_cast<std::size_t>(rank - first), n = static_cast<std::size_t>(count);
    return {n_stats * s / n, n_stats * (s + 1) / n};
  }
};

// One statistics rank's columns once every chunk is merged, as it sends them to rank 0: the
// statistics of columns first .. first + stats.size() - 1, with the thread CPU time its merging took.
struct StatsPart {
  std::size_t first = 0;
  std::vector<statistics::Stats> stats;
  std::vector<std::uint8_t> resolved;
  std::size_t kept_values = 0;
  double merge_cpu_s = 0.0;
};

// Little-endian bytes (statistics rank -> rank 0); the reader throws std::runtime_error for bytes
// that are not one image.
std::string to_bytes(const StatsPart& s);
StatsPart read_stats_part(std::string_view bytes);

// Rank 0: the parts of every statistics rank (any order) as the file's statistics. Throws
// std::runtime_error unless they cover the layout's statistics columns once each.
StreamedStats assemble_streamed_stats(const campaign::RecordLayout& layout, std::vector<StatsPart> parts);

// The merged statistics of a range of the statistics columns (all of them by default).
class ChunkStats {
 public:
  explicit ChunkStats(const campaign::RecordLayout& layout);
  ChunkStats(const campaign::RecordLayout& layout, ColumnRange columns);
  ColumnRange columns() const { return range_; }
  bool seeded() const { return seeded_; }
  // The first windows of its columns (once; ChunkBuilder::first_windows). Throws
  // std::runtime_error for another count or a window whose ends are not ordered.
  void seed(const std::vector<statistics::Windows>& w);
  std::vector<statistics::Windows> windows() const;
  // Chunk `index`'s summaries, one per column of its range. Throws std::runtime_error before a seed,
  // for another count, or a chunk merged twice.
  void merge(std::int64_t index, const std::vector<statistics::ChunkSummary>& summaries);
  std::int64_t merged() const { return merged_; }
  // Its columns' statistics. Throws std::runtime_error unless chunks 0 .. n_chunks - 1 are merged,
  // and no other.
  StatsPart calc_part(std::int64_t n_chunks) const;
  // Every column's (a ChunkStats of all the columns): assemble_streamed_stats of its one part.
  StreamedStats calc_stats(std::int64_t n_chunks) const;

 private:
  const campaign::RecordLayout& L_;
  ColumnRange range_;
  bool seeded_ = false;
  std::int64_t merged_ = 0;
  std::vector<statistics::ColumnStats> col_;  // one per column of range_
};

}  // namespace truss::results
