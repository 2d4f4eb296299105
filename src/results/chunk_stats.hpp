// The statistics of the output columns, merged from the chunks' summaries on one rank (the
// statistics rank, engine.hpp): each column's ColumnStats (statistics/column_stats.hpp), the windows
// the owners summarise their chunks against, and at the end the streamed statistics that rank 0
// writes to /stats. Its work is per chunk summary, never per run; the result is a function of the
// chunks' values alone (the windows only decide what is kept): the same on any number of ranks,
// whichever rank merges, and after --resume.
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
};

// Little-endian bytes (statistics rank -> rank 0); the reader throws std::runtime_error for bytes
// that are not one image.
std::string to_bytes(const StreamedStats& s);
StreamedStats read_streamed_stats(std::string_view bytes);

class ChunkStats {
 public:
  explicit ChunkStats(const campaign::RecordLayout& layout);
  bool seeded() const { return seeded_; }
  // The first windows of every statistics column (once; ChunkBuilder::first_windows). Throws
  // std::runtime_error for another count or a window whose ends are not ordered.
  void seed(const std::vector<statistics::Windows>& w);
  std::vector<statistics::Windows> windows() const;
  // Chunk `index`'s summaries, one per statistics column. Throws std::runtime_error before a seed,
  // for another count, or a chunk merged twice.
  void merge(std::int64_t index, const std::vector<statistics::ChunkSummary>& summaries);
  std::int64_t merged() const { return merged_; }
  // Throws std::runtime_error unless chunks 0 .. n_chunks - 1 are merged, and no other.
  StreamedStats calc_stats(std::int64_t n_chunks) const;

 private:
  const campaign::RecordLayout& L_;
  ChunkColumns cols_;
  bool seeded_ = false;
  std::int64_t merged_ = 0;
  std::vector<statistics::ColumnStats> col_;  // one per statistics column
};

}  // namespace truss::results
