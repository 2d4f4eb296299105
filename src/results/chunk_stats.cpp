// The merged statistics of the output columns (chunk_stats.hpp).
#include "results/chunk_stats.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "util/bytes.hpp"

namespace truss::results {

using campaign::Scale;

ChunkStats::ChunkStats(const campaign::RecordLayout& layout) : ChunkStats(layout, {0, ChunkColumns(layout).n_stats}) {}

ChunkStats::ChunkStats(const campaign::RecordLayout& layout, ColumnRange columns) : L_(layout), range_(columns) {
  if (columns.begin > columns.end || columns.end > ChunkColumns(layout).n_stats)
    throw std::invalid_argument(fmt::format("statistics columns {} to {} of {}", columns.begin, columns.end,
                                            ChunkColumns(layout).n_stats));
  col_.resize(columns.size());
}

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

StatsPart ChunkStats::calc_part(std::int64_t n_chunks) const {
  StatsPart p;
  p.first = range_.begin;
  for (std::size_t k = 0; k < col_.size(); ++k) {
    if (!col_[k].complete(n_chunks))
      throw std::runtime_error(fmt::format("internal: the statistics of column {} miss a chunk", range_.begin + k));
    bool ok = true;
    p.stats.push_back(col_[k].calc_stats(ok));
    p.resolved.push_back(ok);
    p.kept_values += col_[k].kept_values();
  }
  return p;
}

StreamedStats ChunkStats::calc_stats(std::int64_t n_chunks) const {
  return assemble_streamed_stats(L_, {calc_part(n_chunks)});
}

StreamedStats assemble_streamed_stats(const campaign::RecordLayout& layout, std::vector<StatsPart> parts) {
  std::sort(parts.begin(), parts.end(), [](const StatsPart& a, const StatsPart& b) { return a.first < b.first; });
  std::vector<statistics::Stats> all;
  std::vector<std::uint8_t> resolved;
  StreamedStats s;
  for (StatsPart& p : parts) {
    if (p.first != all.size())
      throw std::runtime_error(fmt::format("streamed statistics: a part from column {} after {} columns", p.first,
                                           all.size()));
    all.insert(all.end(), p.stats.begin(), p.stats.end());
    resolved.insert(resolved.end(), p.resolved.begin(), p.resolved.end());
    s.kept_values += p.kept_values;
  }
  const ChunkColumns cols(layout);
  if (all.size() != cols.n_stats)
    throw std::runtime_error(fmt::format("streamed statistics: {} columns of {}", all.size(), cols.n_stats));
  for (const ChunkColumn& c : cols.columns) {
    if (c.stats < 0) continue;
    const auto k = static_cast<std::size_t>(c.stats);
    if (layout.fields()[static_cast<std::size_t>(c.field)].scale == Scale::none) {
      s.f64.push_back(all[k]);
      s.f64_resolved.push_back(resolved[k]);
      continue;
    }
    const auto from = static_cast<std::ptrdiff_t>(k), to = static_cast<std::ptrdiff_t>(k + c.width);
    s.bays.emplace_back(all.begin() + from, all.begin() + to);
    s.bays_resolved.emplace_back(resolved.begin() + from, resolved.begin() + to);
  }
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

// u64 first column, u64 kept values, f64 merge CPU, u32 n, n x stats (i64 count, f64 mean, std,
// min, max, percentiles, u8 resolved).
std::string to_bytes(const StatsPart& s) {
  std::string out;
  util::put(out, static_cast<std::uint64_t>(s.first));
  util::put(out, static_cast<std::uint64_t>(s.kept_values));
  util::put(out, s.merge_cpu_s);
  util::put(out, static_cast<std::uint32_t>(s.stats.size()));
  for (std::size_t i = 0; i < s.stats.size(); ++i) put_stats(out, s.stats[i], s.resolved[i]);
  return out;
}

StatsPart read_stats_part(std::string_view bytes) {
  util::ByteReader in(bytes, "streamed statistics");
  StatsPart s;
  s.first = static_cast<std::size_t>(in.get<std::uint64_t>());
  s.kept_values = static_cast<std::size_t>(in.get<std::uint64_t>());
  s.merge_cpu_s = in.get<double>();
  s.resolved.resize(get_count(in, kStatsBytes));
  for (std::uint8_t& ok : s.resolved) s.stats.push_back(get_stats(in, ok));
  in.expect_end();
  return s;
}

}  // namespace truss::results
