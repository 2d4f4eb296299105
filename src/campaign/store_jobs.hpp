// The wire format of the results file's encoding jobs (result_store.hpp): rank 0 packages each
// completed dataset chunk as a job, any rank encodes it (encode_job_output), rank 0 writes the
// output. Both directions carry parts with a fixed header; see JobHeader.
#pragma once
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>

#include <fmt/format.h>

namespace truss::campaign {

// Encoding job (rank 0 -> encoder): one or more parts, each a header, one dataset chunk's raw
// bytes and, for an output column, a statistics request; its output (encoder -> job_done): the same
// parts with the stored bytes and the columns' chunk summaries (column_stats.hpp). Little-endian.
// A statistics request: u32 rows (runs in the chunk), u32 width (columns), rows bytes (1: an ok
// run), width x Windows; its answer: width ChunkSummary.
struct JobHeader {
  std::uint32_t dataset = 0;  // index into Datasets::direct
  std::uint32_t elem_size = 0;
  std::int64_t chunk = 0;     // chunk index (first row / chunk_runs)
  std::int32_t level = 0;
  std::uint32_t mask = 0;     // output: the filter mask of the stored bytes
  std::uint64_t bytes = 0;    // chunk bytes after the header
  std::uint64_t stats_bytes = 0;  // statistics request (job) or summaries (output) after them
};
inline constexpr std::size_t kJobHeader = sizeof(JobHeader);
// JobHeader::level of a part that asks for the statistics only (--compression 0: the raw chunk is
// already written; its output part has no bytes, only the summaries).
inline constexpr std::int32_t kStatsOnly = -1;
// Small dataset chunks (the scalar columns, 32 kB each) are grouped into jobs of about this size,
// so that a chunk of runs makes some twenty jobs: fewer than the batches that carry them.
inline constexpr std::size_t kJobBytes = std::size_t{1} << 20;

// Calls f(header, bytes, stats) for each part of a job or of its output.
template <class F>
inline void for_each_part(std::string_view job, const char* what, F&& f) {
  while (!job.empty()) {
    JobHeader h;
    if (job.size() < kJobHeader) throw std::runtime_error(fmt::format("{}: a part of {} bytes, shorter than its header", what, job.size()));
    std::memcpy(&h, job.data(), kJobHeader);
    if (h.bytes > job.size() - kJobHeader || h.stats_bytes > job.size() - kJobHeader - h.bytes)
      throw std::runtime_error(fmt::format("{}: a part of {} + {} bytes in {}", what, h.bytes, h.stats_bytes, job.size()));
    f(h, job.substr(kJobHeader, h.bytes), job.substr(kJobHeader + h.bytes, h.stats_bytes));
    job.remove_prefix(kJobHeader + h.bytes + h.stats_bytes);
  }
}

}  // namespace truss::campaign
