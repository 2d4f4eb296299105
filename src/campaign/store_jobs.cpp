// Encoding jobs (store_jobs.hpp): what a worker, or rank 0, does with one.
#include "campaign/store_jobs.hpp"

#include "campaign/chunk_codec.hpp"
#include "campaign/column_stats.hpp"
#include "campaign/result_store.hpp"

namespace truss::campaign {

namespace {

// The answer to a statistics request (JobHeader) for the chunk `raw` (rows x width float64).
void append_summaries(std::string_view raw, std::string_view request, std::string& out) {
  std::uint32_t rw[2] = {0, 0};
  if (request.size() < sizeof rw) throw std::runtime_error("a statistics request cut short");
  std::memcpy(rw, request.data(), sizeof rw);
  const std::size_t rows = rw[0], width = rw[1];
  request.remove_prefix(sizeof rw);
  if (width == 0 || request.size() < rows || raw.size() < 8 * rows * width)
    throw std::runtime_error(fmt::format("a statistics request for {} x {} values of a {}-byte chunk", rows, width, raw.size()));
  const auto* use = reinterpret_cast<const std::uint8_t*>(request.data());
  request.remove_prefix(rows);
  for (std::size_t b = 0; b < width; ++b) append_summary(out, calc_chunk_summary(raw.data() + 8 * b, rows, width, use, read_windows(request)));
}

}  // namespace

void encode_job_output(std::string_view job, std::string& out) {
  out.clear();
  std::string enc;
  for_each_part(job, "an encoding job", [&](JobHeader h, std::string_view raw, std::string_view request) {
    enc.clear();
    if (h.level != kStatsOnly) h.mask = encode_chunk(raw, h.elem_size, h.level, enc);
    h.bytes = enc.size();
    const std::size_t at = out.size();
    out.append(reinterpret_cast<const char*>(&h), kJobHeader);
    out += enc;
    if (h.stats_bytes == 0) return;
    append_summaries(raw, request, out);
    h.stats_bytes = out.size() - at - kJobHeader - h.bytes;
    std::memcpy(out.data() + at, &h, kJobHeader);
  });
}

}  // namespace truss::campaign
