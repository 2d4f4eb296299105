// The statistics columns whose streamed windows missed their order statistics (subset simulation's
// chains drift with the run index), computed from the stored file by whichever rank is given them,
// so that no rank reads every result back: rank 0 lists them by dataset with the places of the
// dataset's stored chunks (find_read_back), each rank decodes its share of the datasets from the
// file with the results' codec and computes their exact percentiles (calc_read_back:
// statistics::calc_stats, the same order statistics as numpy's), and rank 0 puts the answers in
// the streamed statistics (apply_read_back). A column left unanswered is read back by rank 0 when
// it writes /stats (summary_h5.hpp).
#pragma once
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/record.hpp"
#include "results/chunk_stats.hpp"

namespace truss::results {

// The columns of `rows` rows read back at once: at most 64 MiB of them (at least one column); more
// columns take another pass over the dataset's chunks.
inline std::int64_t find_read_back_group(std::int64_t rows) {
  constexpr std::int64_t kReadBackBytes = std::int64_t{64} << 20;
  return std::max<std::int64_t>(1, kReadBackBytes / (8 * std::max<std::int64_t>(rows, 1)));
}

// One dataset's columns to read back: its stored chunks in row order (file offset, stored bytes,
// filter mask), its rows, and the columns with where their statistics go (`group` -1: the f64
// output `index`; else per-bay field `group`, bay `index`, of StreamedStats).
struct ReadBackJob {
  struct Chunk {
    std::uint64_t offset = 0, bytes = 0;
    std::uint32_t mask = 0;
  };
  struct Column {
    std::int64_t column = 0;  // in the dataset's row
    std::int32_t group = -1;
    std::int64_t index = 0;
  };
  std::string path;  // the dataset, for messages
  std::int64_t rows = 0, chunk_rows = 0, width = 1;
  bool filtered = true;
  std::vector<Chunk> chunks;
  std::vector<Column> columns;
  std::uint64_t stored_bytes() const;  // what decoding it reads: its share of the work
};

// What a rank found: the exact percentiles of one column of a job (statistics::calc_stats's; the
// streamed moments, minimum and maximum stand).
struct ReadBackAnswer {
  std::int32_t group = -1;
  std::int64_t index = 0;
  std::array<double, statistics::kStatTargets> percentiles{};
};

// Rank 0, every chunk placed: the datasets with columns not resolved in `s`, n rows each.
std::vector<ReadBackJob> find_read_back(hid_t file, const campaign::RecordLayout& layout, const StreamedStats& s,
                                        std::int64_t n);
// Any rank: the job's columns from the file at `path` (pread of the stored chunks,
// ChunkCodec::decode; `group` columns a pass, 0: find_read_back_group's), their percentiles over the
// runs with ok[i] != 0. Throws std::runtime_error when a chunk cannot be read or decoded.
std::vector<ReadBackAnswer> calc_read_back(const std::string& path, const ReadBackJob& job,
                                           const std::vector<std::uint8_t>& ok, std::size_t group = 0);
// Rank 0: the answers in place (each column resolved, counted in s.read_back).
void apply_read_back(StreamedStats& s, const std::vector<ReadBackAnswer>& answers);

// Little-endian bytes of the jobs with the file and the ok runs (rank 0 -> every rank), and of
// answers (every rank -> rank 0); the readers throw std::runtime_error for bytes that are not one.
struct ReadBackPlan {
  std::string path;
  std::vector<std::uint8_t> ok;
  std::vector<ReadBackJob> jobs;
};
std::string to_bytes(const ReadBackPlan& p);
ReadBackPlan read_read_back_plan(std::string_view bytes);
std::string to_bytes(const std::vector<ReadBackAnswer>& a);
std::vector<ReadBackAnswer> read_read_back_answers(std::string_view bytes);

// The jobs of `rank` of `size`: the largest first (stored bytes, then order), each to the rank
// with the least so far (ties: the lowest rank): the same on every rank.
std::vector<std::size_t> find_jobs_of(const std::vector<ReadBackJob>& jobs, int rank, int size);

}  // namespace truss::results
