// Rank 0's results of a running campaign, streamed into the open results file in run-index
// chunks. Runs arrive in any order; a chunk's rows are held until every one of its runs has
// arrived, then written to /runs and /timing and the chunk's memory is reused. Runs are handed out
// in index order, so only the chunks around the scheduling front are in memory: rank 0's memory
// is (chunks in flight) x (chunk rows) x (record size) plus one byte per run, not n x 4.5 kB.
// What is written does not depend on the order of arrival, so the file holds the same values on
// any number of ranks and after --resume.
#pragma once
#include <array>
#include <hdf5.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "campaign/run_record.hpp"
#include "io/h5_util.hpp"

namespace truss::campaign {

// How the per-run datasets are stored.
struct StoreOptions {
  std::int64_t chunk_runs = 4096;  // rows per chunk: 32 kB per float64 column, a few chunks in memory
  int deflate_level = 1;           // zlib level (0: no compression); 1 keeps rank 0's per-result cost low
  std::string validate() const;
};

class ResultStore {
 public:
  // Creates /runs (and its bays, inputs groups) and /timing's per-run datasets in `file`, chunked
  // by chunk_runs rows, shuffled and deflated unless deflate_level is 0.
  ResultStore(hid_t file, const CampaignContext& ctx, const StoreOptions& opts);
  ~ResultStore();
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;

  void add(const RunRecord& r, int session);  // throws std::runtime_error for a bad or repeated index
  bool has(std::int64_t run) const { return done_[static_cast<std::size_t>(run)] != 0; }
  std::int64_t n_runs() const { return n_; }
  std::int64_t n_done() const { return n_done_; }
  std::int64_t n_failed() const { return n_failed_; }
  // Runs per RunStatus value so far (restored and new), for progress lines by status name.
  const std::array<std::int64_t, sim::kRunStatusCount>& status_counts() const { return status_counts_; }
  std::int64_t chunk_runs() const { return chunk_; }
  std::size_t peak_chunks_in_memory() const { return peak_chunks_; }
  // Throws std::runtime_error unless every run has arrived (and so every chunk is written).
  void check_complete() const;

 private:
  struct Chunk;
  struct Datasets;
  Chunk& chunk_for(std::int64_t run);
  void write_chunk(const Chunk& c);
  void attach_scales(hid_t file, Datasets& d);

  const CampaignContext& ctx_;
  std::int64_t n_, chunk_;
  int deflate_;
  std::vector<std::uint8_t> done_;
  std::int64_t n_done_ = 0, n_failed_ = 0;
  std::array<std::int64_t, sim::kRunStatusCount> status_counts_{};
  std::map<std::int64_t, std::unique_ptr<Chunk>> open_;  // by chunk index
  std::vector<std::unique_ptr<Chunk>> spare_;              // written chunks, memory kept for reuse
  std::size_t peak_chunks_ = 0;
  std::unique_ptr<Datasets> ds_;
};

// Reading the finished /runs back (statistics, sensitivity): a 1-D float64 column; columns
// col0 .. col0 + cols - 1 of an n x width dataset, read in blocks of block_rows whole rows (whole
// chunks: each is decompressed once per call).
std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n);
std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n, std::int64_t width,
                                                  std::int64_t col0, std::int64_t cols, std::int64_t block_rows);
std::vector<std::int8_t> read_status(hid_t file, std::int64_t n);

}  // namespace truss::campaign
