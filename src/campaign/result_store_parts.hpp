// The parts of a ResultStore that result_store.cpp (datasets, chunk completion, jobs, statistics)
// and result_records.cpp (records in, chunk buffers) share. Internal to those two files.
#pragma once
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/column_stats.hpp"
#include "campaign/result_store.hpp"
#include "io/h5_util.hpp"

namespace truss::campaign {

// A record's head (RunRecord::append_bytes): i64 run, i8 status, i32 rank, f64 wall time at byte
// kRecordWall, u32 message length; the message follows it.
inline constexpr std::size_t kRecordHead = 8 + 1 + 4 + 8 + 4;
inline constexpr std::size_t kRecordWall = 13;
struct RecordHead {
  std::int64_t run = -1;
  std::int8_t status = 0;
  std::int32_t rank = 0;
  std::uint32_t message_bytes = 0;
};
// The head of rec, which must hold at least kRecordHead bytes.
inline RecordHead read_record_head(std::string_view rec) {
  RecordHead h;
  std::memcpy(&h.run, rec.data(), 8);
  h.status = static_cast<std::int8_t>(rec[8]);
  std::memcpy(&h.rank, rec.data() + 9, 4);
  std::memcpy(&h.message_bytes, rec.data() + kRecordWall + 8, 4);
  return h;
}

// Streaming statistics of the output columns (float64 per run, per bay): tracker k of dataset j
// is first[j] + column; first[j] < 0 for the datasets without statistics.
struct ResultStore::Tracking {
  std::vector<ColumnStats> col;
  std::vector<std::int64_t> first;
};

struct ResultStore::Chunk {
  std::int64_t first = 0, rows = 0, filled = 0;
  std::vector<std::string> buf;  // per direct dataset: a job header, then chunk rows x width values (zero past rows)
  std::vector<std::string> message;
};

// The per-run datasets written with H5Dwrite_chunk ("direct"), in record order, and /runs/message
// (variable-length strings go through H5Dwrite).
struct ResultStore::Datasets {
  std::vector<io::h5::Handle> keep;  // groups
  io::h5::Handle status_type = io::h5::status_enum_type();
  io::h5::Handle str_type = io::h5::string_type();
  struct Direct {
    io::h5::Handle ds;
    std::size_t elem = 8, width = 1;  // bytes per value, values per row
    int rank = 1;                     // dataspace rank (1: a column, 2: rows x width)
  };
  std::vector<Direct> direct;  // run_index, status, run_wall_time_s, rank, session, f64, i64, bays, inputs
  std::size_t f64_0 = 0, i64_0 = 0, bays_0 = 0, inputs_0 = 0;  // first index of each group in `direct`
  std::unique_ptr<io::h5::Handle> message;
};

}  // namespace truss::campaign
