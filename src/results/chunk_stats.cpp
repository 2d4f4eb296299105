// The merged statistics of the output columns (chunk_stats.hpp).
#include "results/chunk_stats.hpp"

#include <stdexcept>

#include <fmt/format.h>

#include "util/bytes.hpp"

namespace truss::results {

using campaign::Scale;

ChunkStats::ChunkStats(const campaign::RecordLayout& layout) : L_(layout), cols_(layout) { col_.resize(cols_.n_stats); }

void ChunkStats::seed(const std::vector<statistics::Windows>& w) {
  if (seeded_) return;
  if (w.size() != col_.size())
    throw std::runtime_error(
        fmt::format("first windows of {} columns for {} statistics columns", w.size(), col_.size()));
  for (const statistics::Windows& c : w)
    for (const statistics::Window& x : c)
      if (!(x.lo <= x.hi)) throw std::runtime_error(fmt::format("a first window [{}, {}]", x.lo, x.hi));
  for (std::size_t k = 0; k < col_.size(); ++k) col_[k].seed(w[k]);
  seeded_ = true;
}

std::vector<statistics::Windows> ChunkStats::windows() const {
  std::vector<statistics::Windows> w;
  w.reserve(col_.size());
  for (const auto& c : col_) w.push_back(c.windows());
  return w;
}

void ChunkStats::merge(std::int64_t index, const std::vector<statistics::ChunkSummary>& summaries) {
  if (!seeded_) throw std::runtime_error(fmt::format("chunk {}: statistics before the first windows", index));
  if (summaries.size() != col_.size())
    throw std::runtime_error(
        fmt::format("chunk {}: {} summaries for {} statistics columns", index, summaries.size(), col_.size()));
  for (std::size_t k = 0; k < col_.size(); ++k) col_[k].add(index, summaries[k]);
  ++merged_;
}

StreamedStats ChunkStats::calc_stats(std::int64_t n_chunks) const {
  StreamedStats s;
  auto one = [&](std::size_t k, std::vector<std::uint8_t>& resolved) {
    if (!col_[k].complete(n_chunks))
      throw std::runtime_error(fmt::format("internal: the statistics of column {} miss a chunk", k));
    bool ok = true;
    const statistics::Stats st = col_[k].calc_stats(ok);
    resolved.push_back(ok);
    return st;
  };
  for (const ChunkColumn& c : cols_.columns) {
    if (c.stats < 0) continue;
    const auto k = static_cast<std::size_t>(c.stats);
    if (L_.fields()[static_cast<std::size_t>(c.field)].scale == Scale::none) {
      s.f64.push_back(one(k, s.f64_resolved));
      continue;
    }
    auto& st = s.bays.emplace_back();
    auto& ok = s.bays_resolved.emplace_back();
    for (std::size_t b = 0; b < c.width; ++b) st.push_back(one(k + b, ok));
  }
  for (const auto& c : col_) s.kept_values += c.kept_values();
  return s;
}

namespace {

void put_stats(std::string& out, const statistics::Stats& s, std::uint8_t resolved) {
  util::put(out, s.count);
  for (double v : {s.mean, s.std, s.min, s.max}) util::put(out, v);
  for (double v : s.percentiles) util::put(out, v);
  util::put(out, resolved);
}

statistics::Stats get_stats(util::ByteReader& in, std::uint8_t& resolved) {
  statistics::Stats s;
  s.count = in.get<std::int64_t>();
  for (double* v : {&s.mean, &s.std, &s.min, &s.max}) *v = in.get<double>();
  for (double& v : s.percentiles) v = in.get<double>();
  resolved = in.get<std::uint8_t>();
  return s;
}

constexpr std::size_t kStatsBytes = 8 * (5 + statistics::kStatTargets) + 1;

std::size_t get_count(util::ByteReader& in, std::size_t item_bytes) {
  const auto n = in.get<std::uint32_t>();
  if (n > in.left() / item_bytes)
    throw std::runtime_error(fmt::format("streamed statistics: {} items announced, {} bytes left", n, in.left()));
  return n;
}

}  // namespace

// u64 kept values, u32 n, n x stats (i64 count, f64 mean, std, min, max, percentiles, u8 resolved),
// u32 fields, each u32 bays and as many stats.
std::string to_bytes(const StreamedStats& s) {
  std::string out;
  util::put(out, static_cast<std::uint64_t>(s.kept_values));
  util::put(out, static_cast<std::uint32_t>(s.f64.size()));
  for (std::size_t i = 0; i < s.f64.size(); ++i) put_stats(out, s.f64[i], s.f64_resolved[i]);
  util::put(out, static_cast<std::uint32_t>(s.bays.size()));
  for (std::size_t f = 0; f < s.bays.size(); ++f) {
    util::put(out, static_cast<std::uint32_t>(s.bays[f].size()));
    for (std::size_t b = 0; b < s.bays[f].size(); ++b) put_stats(out, s.bays[f][b], s.bays_resolved[f][b]);
  }
  return out;
}

StreamedStats read_streamed_stats(std::string_view bytes) {
  util::ByteReader in(bytes, "streamed statistics");
  StreamedStats s;
  s.kept_values = static_cast<std::size_t>(in.get<std::uint64_t>());
  s.f64_resolved.resize(get_count(in, kStatsBytes));
  for (std::uint8_t& ok : s.f64_resolved) s.f64.push_back(get_stats(in, ok));
  const std::size_t fields = get_count(in, 4);
  for (std::size_t f = 0; f < fields; ++f) {
    auto& st = s.bays.emplace_back();
    auto& ok = s.bays_resolved.emplace_back(get_count(in, kStatsBytes));
    for (std::uint8_t& r : ok) st.push_back(get_stats(in, r));
  }
  in.expect_end();
  return s;
}

}  // namespace truss::results
