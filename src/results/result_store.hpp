// Rank 0's results of a running campaign, streamed into the open results file in chunks of
// consecutive run indices. Runs arrive in any order; each record is copied into the row of its
// chunk; a chunk whose rows have all arrived is written one dataset at a time (write_next, between
// rank 0's other work, so that no worker waits for a whole chunk: a 4,096-run Table-1 chunk is
// 18 MB), each dataset chunk shuffled and deflated (chunk_codec.hpp) and written with
// H5Dwrite_chunk, and the statistics of its output columns merged (statistics/column_stats.hpp).
// Runs are handed out in index order, so only the chunks around the scheduling front are in
// memory. What is written does not depend on the order of arrival: the file holds the same values
// on any number of ranks and after --resume.
//
// The datasets are extendible: a method that adds rounds adds rows (extend).
#pragma once
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "campaign/record.hpp"
#include "io/h5_util.hpp"
#include "results/chunk_codec.hpp"
#include "statistics/column_stats.hpp"
#include "statistics/stats.hpp"

namespace truss::results {

// How the per-run datasets are stored.
struct StoreOptions {
  std::int64_t chunk_runs = 4096;  // rows per chunk: 32 kB per float64 column
  int deflate_level = 1;           // zlib level (0: no filter); 1: the fastest, most of level 9's ratio
  std::string validate() const;
};

// Rows per chunk for a campaign of n runs (its first round): 4,096 (32 kB a float64 column) from
// 32,768 runs up; smaller campaigns get at least 8 chunks of at least 1,024 rows (and no chunk
// longer than the campaign), so that writing the chunks overlaps the runs instead of all falling
// on the end. Each chunk of each dataset has fixed costs (an H5Dwrite_chunk, a deflate call, each
// column's statistics merged), so fewer, longer chunks cost rank 0 less a result, for a longer last
// chunk (written after the last run; docs/benchmarks.md). A function of the campaign alone: the
// file is the same on any number of ranks and after --resume.
inline std::int64_t find_chunk_runs(std::int64_t n_runs) {
  const std::int64_t rows = std::clamp<std::int64_t>(n_runs / 8, 1024, 4096);
  return std::max<std::int64_t>(1, std::min(rows, n_runs));
}

// The statistics of the output columns, from the chunks as they were written: per float64 output
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
  // Creates /runs (with its bays and inputs groups) and /timing's per-run datasets in `file`, no
  // rows yet, one dataset per record field plus /runs/message and /timing/session.
  ResultStore(hid_t file, const campaign::RecordLayout& layout, const StoreOptions& opts);
  ~ResultStore();
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;

  void extend(std::int64_t n_runs);  // rows 0 .. n_runs - 1 (never fewer than before)
  std::int64_t n_runs() const { return n_; }
  bool has(std::int64_t run) const { return done_[static_cast<std::size_t>(run)] != 0; }
  std::int64_t n_done() const { return n_done_; }
  const StatusCounts& status_counts() const { return status_counts_; }

  // A record of this layout (RecordLayout::check has passed) into its chunk's row, with the
  // session that stored it. Throws std::runtime_error for a run out of range or already stored.
  void add(const campaign::RecordView& rec, std::int64_t session);
  bool write_pending() const { return !complete_.empty(); }
  void write_next();  // one dataset of the oldest chunk whose rows have all arrived
  // Writes every chunk, the last one too if it is partial. Throws std::runtime_error unless every
  // run has arrived.
  void finish();
  StreamedStats calc_stats() const;  // after finish
  std::int64_t chunk_runs() const { return chunk_; }
  std::size_t peak_chunks_in_memory() const { return peak_chunks_; }

 private:
  struct Chunk;
  struct Dataset;
  Chunk& chunk_for(std::int64_t run);
  void create_datasets(hid_t file);
  void write_dataset(Chunk& c, const Dataset& d, std::int64_t rows);  // zeroes the rows past `rows`
  void merge_stats(const Dataset& d, const char* block, std::int64_t chunk, const std::vector<std::uint8_t>& use,
                   std::int64_t rows);

  const campaign::RecordLayout& L_;
  std::int64_t n_ = 0, chunk_;
  int deflate_;
  std::vector<std::uint8_t> done_;
  std::int64_t n_done_ = 0;
  StatusCounts status_counts_{};
  std::vector<Dataset> ds_;
  std::vector<io::h5::Handle> groups_;
  std::map<std::int64_t, std::unique_ptr<Chunk>> open_;  // by chunk index
  std::deque<std::int64_t> complete_;                     // chunks to write, in the order they completed
  std::size_t next_dataset_ = 0;                          // of complete_.front()
  std::size_t peak_chunks_ = 0;
  std::vector<statistics::ColumnStats> col_;                // one per output column (per bay for per-bay fields)
  statistics::ChunkSummary summary_;                        // one column's chunk summary, its room used again
  ChunkCodec codec_;                                      // shuffle + deflate of each dataset chunk
  std::string encoded_;                                   // a dataset chunk after the filters
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
