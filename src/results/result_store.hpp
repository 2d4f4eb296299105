// Rank 0's side of the results file's per-run datasets. It creates them (extendible: a method that
// adds rounds adds rows), and for each complete chunk that a builder reports (chunk_builder.hpp) it
// places the chunk's datasets in the file (HDF5 allocates and indexes them through the placement
// driver, placement_driver.hpp; the builder writes their bytes there), writes the chunk's messages
// and merges the summaries of its statistics columns (statistics/column_stats.hpp). The first
// windows come from the first builder with a complete chunk. Its work is per chunk, never per run; what it
// writes does not depend on which rank built a chunk or when: the file holds the same values, and
// the same chunk bytes, on any number of ranks and after --resume.
#pragma once
#include <hdf5.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "campaign/record.hpp"
#include "io/h5_util.hpp"
#include "results/chunk_builder.hpp"
#include "results/placement_driver.hpp"
#include "statistics/column_stats.hpp"
#include "statistics/stats.hpp"

namespace truss::results {

// The statistics of the output columns, from the chunks as they were placed: per float64 output
// and per bay of each per-bay output, in RecordLayout order. `resolved` 0: a percentile's order
// statistics were not kept (its percentiles are NaN): compute them from the stored column.
struct StreamedStats {
  std::vector<statistics::Stats> f64;
  std::vector<std::uint8_t> f64_resolved;
  std::vector<std::vector<statistics::Stats>> bays;  // [field][bay - 1]
  std::vector<std::vector<std::uint8_t>> bays_resolved;
  std::size_t kept_values = 0;  // values held for the percentiles, all columns
};

using StatusCounts = std::array<std::int64_t, sim::kRunStatusCount>;  // runs per RunStatus value

class ResultStore {
 public:
  // Creates /runs (with its bays and inputs groups) and /timing's per-run datasets in `file` (opened
  // through the placement driver with `placement`), no rows yet, one dataset per record field plus
  // /runs/message and /timing/session.
  ResultStore(hid_t file, PlacementState& placement, const campaign::RecordLayout& layout, const StoreOptions& opts);
  ~ResultStore();
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;

  void extend(std::int64_t n_runs);  // rows 0 .. n_runs - 1 (never fewer than before)
  std::int64_t n_runs() const { return n_; }
  std::int64_t chunk_runs() const { return chunk_; }

  bool seeded() const { return seeded_; }
  // The first windows of every statistics column (once; ChunkBuilder::first_windows). Throws
  // std::runtime_error for another count or a window whose ends are not ordered.
  void seed(const std::vector<statistics::Windows>& w);
  std::vector<statistics::Windows> windows() const;
  // A complete chunk of the rows so far: its datasets placed (their addresses, in dataset order),
  // its messages written and its statistics merged. Throws std::runtime_error for a chunk placed
  // twice or out of range, a report of another row count or shape, or statistics before a seed.
  std::vector<ChunkAddress> place(const ChunkReport& r);
  std::int64_t chunks_placed() const { return n_placed_; }
  // Throws std::runtime_error unless every chunk of the n_runs rows is placed.
  void finish() const;
  StreamedStats calc_stats() const;  // after finish

 private:
  struct Dataset;
  void create_datasets(hid_t file, int deflate);
  std::size_t dataset_of(std::size_t column) const;
  void write_messages(const ChunkReport& r);

  const campaign::RecordLayout& L_;
  PlacementState& placement_;
  ChunkColumns cols_;
  std::int64_t n_ = 0, chunk_;
  std::vector<Dataset> ds_;  // cols_'s datasets, then /runs/message
  std::vector<io::h5::Handle> groups_;
  std::vector<std::uint8_t> placed_;  // by chunk
  std::int64_t n_placed_ = 0;
  bool seeded_ = false;
  std::vector<statistics::ColumnStats> col_;  // one per statistics column
};

// Reading the finished /runs back (statistics, sensitivity): a 1-D float64 column; columns
// col0 .. col0 + cols - 1 of an n x width dataset, read in blocks of block_rows whole rows (whole
// chunks: each is decompressed once per call); the run statuses.
std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n);
std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n,
                                                  std::int64_t width, std::int64_t col0, std::int64_t cols,
                                                  std::int64_t block_rows);
std::vector<std::int8_t> read_status(hid_t file, std::int64_t n);
// The message of one run (/runs/message[run]).
std::string read_message(hid_t file, std::int64_t run);

}  // namespace truss::results
