// Rank 0's side of the results file's per-run datasets. It creates them (extendible: a method that
// adds rounds adds rows), and for each complete chunk that a builder reports (chunk_builder.hpp) it
// places the chunk's datasets in the file (HDF5 allocates and indexes them through the placement
// driver, placement_driver.hpp; the builder writes their bytes there), writes the chunk's messages
// (the summaries of its statistics columns go to the statistics ranks, chunk_stats.hpp). Its work is
// per chunk, never per run; what it
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
#include "results/chunk_stats.hpp"
#include "results/placement_driver.hpp"
#include "statistics/column_stats.hpp"
#include "statistics/stats.hpp"

namespace truss::results {

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

  void extend(std::int64_t n_runs);  // rows 0 .. n_runs - 1 (never fewer than before); in the file by place()
  std::int64_t n_runs() const { return n_; }
  std::int64_t chunk_runs() const { return chunk_; }

  // A complete chunk of the rows so far: its datasets placed (their addresses, in dataset order)
  // and its messages written (its statistics are the statistics ranks': chunk_stats.hpp). Throws
  // std::runtime_error for a chunk placed twice or out of range, a report of another row count or shape.
  std::vector<ChunkAddress> place(const ChunkReport& r);
  std::int64_t chunks_placed() const { return n_placed_; }
  // Throws std::runtime_error unless every chunk of the n_runs rows is placed.
  void finish() const;

 private:
  struct Dataset;
  void create_datasets(hid_t file, int deflate);
  std::size_t dataset_of(std::size_t column) const;
  void write_messages(const ChunkReport& r);
  void extend_file_to(std::int64_t rows);

  const campaign::RecordLayout& L_;
  PlacementState& placement_;
  ChunkColumns cols_;
  std::int64_t n_ = 0, chunk_;
  std::int64_t file_rows_ = 0;  // the datasets' rows in the file (<= n_)
  std::vector<Dataset> ds_;  // cols_'s datasets, then /runs/message
  std::vector<io::h5::Handle> groups_;
  std::vector<std::uint8_t> placed_;  // by chunk
  std::int64_t n_placed_ = 0;
};

// Reading the finished /runs back (statistics, sensitivity, failure samples): a 1-D float64
// column; columns col0 .. col0 + cols - 1 of the first n rows of a float64 dataset (each chunk
// decoded once per call); the run statuses. Throws std::runtime_error for a dataset the store did
// not write so (a chunk missing, other filters, a damaged chunk), std::out_of_range for rows or
// columns it does not have.
std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n);
std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n,
                                                  std::int64_t col0, std::int64_t cols);
// Rows `rows` (any order, repeats allowed) of a float64 dataset, rows.size() x width in that order:
// only the chunks that hold them are decoded, each once.
std::vector<double> read_f64_rows(hid_t file, const std::string& path, const std::vector<std::int64_t>& rows);
std::vector<std::int8_t> read_status(hid_t file, std::int64_t n);
// The message of one run (/runs/message[run]).
std::string read_message(hid_t file, std::int64_t run);

}  // namespace truss::results
