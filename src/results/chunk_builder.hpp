// A rank's share of the results file: the chunks of runs it owns, built from their records and
// encoded where the records arrive, so that no rank handles every result (docs/architecture.md, "A
// campaign: the path of one result"). Records arrive in any order; each is scattered on arrival
// into its chunk's column blocks (one per dataset, so that a dataset chunk is one contiguous block).
// The builder reports
//   - a round part when every row of a round that a chunk holds is in: the rows' statuses and the
//     outputs the method observes (what rank 0 needs of them, in run-index order);
//   - a complete chunk when all its rows are in: then it is encoded one dataset at a time (byte
//     shuffle + deflate, chunk_codec.hpp) with the chunk summary of every statistics column against
//     the windows rank 0 gave (statistics/column_stats.hpp), and its rows are freed.
// Everything it produces is a function of the records and the windows alone: the file is the same
// on any number of ranks and after --resume.
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "campaign/record.hpp"
#include "results/chunk_codec.hpp"
#include "statistics/column_stats.hpp"

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
// column's statistics merged), so fewer, longer chunks cost less a result, for a longer last chunk
// (written after the last run; docs/benchmarks.md). A function of the campaign alone: the file is
// the same on any number of ranks and after --resume.
std::int64_t find_chunk_runs(std::int64_t n_runs);

// The per-run datasets in the results file's order: one per record field, then /timing/session
// (/runs/message, variable-length strings, is rank 0's), and their statistics columns: one per
// value of a float64 output (per bay for a per-bay output), in the same order.
struct ChunkColumn {
  static constexpr int kSession = -1;
  int field = kSession;  // the record field, or kSession
  std::size_t elem = 8, width = 1;
  int stats = -1;  // its first statistics column, or -1
};
struct ChunkColumns {
  explicit ChunkColumns(const campaign::RecordLayout& layout);
  std::vector<ChunkColumn> columns;
  std::size_t n_stats = 0;
};
// A half-open range of the statistics columns.
struct ColumnRange {
  std::size_t begin = 0, end = 0;
  std::size_t size() const { return end - begin; }
  bool operator==(const ColumnRange&) const = default;
};

// The rows of one round that one chunk holds, as a method reads them: run first_run + i has
// status[i] and outputs[k][i] for the k-th observed output.
struct RoundPart {
  std::int64_t round = 0, first_run = 0;
  std::vector<std::int8_t> status;
  std::vector<std::vector<double>> outputs;
  std::int64_t size() const { return static_cast<std::int64_t>(status.size()); }
};

// What rank 0 needs of a complete chunk to place it in the file and merge its statistics; the
// encoded bytes stay with their builder until rank 0 has placed them.
struct ChunkReport {
  std::int64_t index = 0, rows = 0;
  std::vector<std::uint64_t> sizes;  // per dataset: encoded bytes
  std::vector<std::uint32_t> masks;  // per dataset: HDF5 filter mask
  std::vector<statistics::ChunkSummary> summaries;  // per statistics column
  std::vector<std::pair<std::int64_t, std::string>> messages;  // (row in the chunk, text), non-empty only
};
struct EncodedChunk {
  ChunkReport report;
  std::vector<std::string> bytes;  // per dataset
};

class ChunkBuilder {
 public:
  // `observed`: the record fields of the float64 outputs the method reads (round parts carry them).
  ChunkBuilder(const campaign::RecordLayout& layout, const StoreOptions& opts, std::vector<std::size_t> observed);
  ~ChunkBuilder();
  ChunkBuilder(const ChunkBuilder&) = delete;
  ChunkBuilder& operator=(const ChunkBuilder&) = delete;

  const campaign::RecordLayout& layout() const { return L_; }
  const ChunkColumns& columns() const { return cols_; }
  std::int64_t chunk_runs() const { return chunk_; }
  // Rounds in order as they are planned (runs first_run .. first_run + n_runs - 1); end_rounds()
  // when the method proposes none: the last chunk ends at the last run.
  void add_round(std::int64_t round, std::int64_t first_run, std::int64_t n_runs);
  void end_rounds();
  // A record (RecordLayout::check passed) stored by `session`. Throws std::runtime_error for a run
  // outside its round or given twice (check: the same test, nothing stored).
  void add(const campaign::RecordView& rec, std::int64_t session);
  void check(const campaign::RecordView& rec) const;
  std::int64_t rounds() const { return static_cast<std::int64_t>(rounds_.size()); }
  std::int64_t n_chunks() const { return (planned_ + chunk_ - 1) / chunk_; }  // of the rows planned

  std::optional<RoundPart> pop_part();         // oldest first
  std::optional<std::int64_t> pop_complete();  // a chunk whose rows are all in, oldest first
  // Encodes the next dataset of complete chunk `chunk` into `out` (its report and bytes), with
  // the summaries of its statistics columns against `windows` (one per statistics column); true
  // when every dataset is done, the chunk's messages are in the report and its rows freed.
  bool encode_step(std::int64_t chunk, const std::vector<statistics::Windows>& windows, EncodedChunk& out);
  // The first statistics windows (statistics::calc_first_windows) of the statistics columns
  // `columns` (all by default), one per column, from a complete chunk's rows.
  std::vector<statistics::Windows> first_windows(std::int64_t chunk) const;
  std::vector<statistics::Windows> first_windows(std::int64_t chunk, ColumnRange columns) const;
  std::size_t open_chunks() const { return open_.size(); }  // in memory: filling, or complete and not encoded
  std::vector<std::int64_t> open_indices() const;
  std::size_t peak_chunks() const { return peak_chunks_; }

 private:
  struct Chunk;
  struct Round {
    std::int64_t round, first, end;
  };
  Chunk& chunk_for(std::int64_t run);
  std::int64_t rows_of(std::int64_t chunk) const;  // its rows planned so far
  bool complete(const Chunk& c) const;
  void check_complete(Chunk& c);
  void push_part(Chunk& c, const Round& r);
  void summarize(const Chunk& c, const ChunkColumn& col, const char* block,
                 const std::vector<statistics::Windows>& windows, EncodedChunk& out);

  const campaign::RecordLayout& L_;
  ChunkColumns cols_;
  std::int64_t chunk_;
  int deflate_;
  std::vector<std::size_t> observed_;
  std::vector<Round> rounds_;
  std::int64_t planned_ = 0;  // rows planned: rounds_'s end
  bool ended_ = false;
  std::map<std::int64_t, std::unique_ptr<Chunk>> open_;  // by chunk index
  std::vector<bool> encoded_;                             // by chunk index: done here, its rows freed
  std::deque<std::int64_t> complete_;
  std::deque<RoundPart> parts_;
  std::size_t peak_chunks_ = 0;
  ChunkCodec codec_;
};

}  // namespace truss::results
