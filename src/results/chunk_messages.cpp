// Byte images of the chunk messages (chunk_messages.hpp).
#include "results/chunk_messages.hpp"

#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "util/bytes.hpp"

namespace truss::results {

using statistics::ChunkSummary;
using statistics::kStatTargets;
using util::ByteReader;
using util::put;

namespace {

// Counts read from bytes: refused past what the bytes could hold, before anything is allocated.
std::size_t get_count(ByteReader& in, std::size_t item_bytes, const char* what) {
  const auto n = in.get<std::uint32_t>();
  if (item_bytes > 0 && n > in.left() / item_bytes)
    throw std::runtime_error(fmt::format("{}: {} items announced, {} bytes left", what, n, in.left()));
  return n;
}

void put_doubles(std::string& out, const std::vector<double>& v) {
  put(out, static_cast<std::uint32_t>(v.size()));
  out.append(reinterpret_cast<const char*>(v.data()), 8 * v.size());
}

void get_doubles(ByteReader& in, std::vector<double>& v, const char* what) {
  v.resize(get_count(in, 8, what));
  if (!v.empty()) std::memcpy(v.data(), in.get_bytes(8 * v.size()).data(), 8 * v.size());
}

void put_windows(std::string& out, const statistics::Windows& w) {
  for (const auto& x : w) {
    put(out, x.lo);
    put(out, x.hi);
  }
}

void get_windows(ByteReader& in, statistics::Windows& w) {
  for (auto& x : w) {
    x.lo = in.get<double>();
    x.hi = in.get<double>();
  }
}

void put_summary(std::string& out, const ChunkSummary& s) {
  put_windows(out, s.window);
  put(out, s.moments.count);
  for (double v : {s.moments.mean, s.moments.m2, s.moments.min, s.moments.max}) put(out, v);
  for (std::size_t t = 0; t < kStatTargets; ++t) {
    put(out, s.below[t]);
    put(out, s.at_lo[t]);
    put(out, s.at_hi[t]);
    put_doubles(out, s.kept[t]);
  }
}

void get_summary(ByteReader& in, ChunkSummary& s) {
  get_windows(in, s.window);
  s.moments.count = in.get<std::int64_t>();
  s.moments.mean = in.get<double>();
  s.moments.m2 = in.get<double>();
  s.moments.min = in.get<double>();
  s.moments.max = in.get<double>();
  for (std::size_t t = 0; t < kStatTargets; ++t) {
    s.below[t] = in.get<std::int64_t>();
    s.at_lo[t] = in.get<std::int64_t>();
    s.at_hi[t] = in.get<std::int64_t>();
    get_doubles(in, s.kept[t], "a chunk summary");
  }
}

}  // namespace

std::string to_bytes(const RoundPart& p) {
  std::string out;
  put(out, p.round);
  put(out, p.first_run);
  put(out, p.size());
  out.append(reinterpret_cast<const char*>(p.status.data()), p.status.size());
  for (const auto& v : p.outputs) out.append(reinterpret_cast<const char*>(v.data()), 8 * v.size());
  return out;
}

RoundPart read_round_part(std::string_view bytes, std::size_t n_outputs) {
  ByteReader in(bytes, "a round part");
  RoundPart p;
  p.round = in.get<std::int64_t>();
  p.first_run = in.get<std::int64_t>();
  const auto n = in.get<std::int64_t>();
  if (n < 0 || static_cast<std::uint64_t>(n) * (1 + 8 * n_outputs) != in.left())
    throw std::runtime_error(fmt::format("a round part of {} rows in {} bytes", n, bytes.size()));
  const std::string_view s = in.get_bytes(static_cast<std::size_t>(n));
  p.status.assign(reinterpret_cast<const std::int8_t*>(s.data()), reinterpret_cast<const std::int8_t*>(s.data()) + n);
  for (std::size_t k = 0; k < n_outputs; ++k) {
    auto& v = p.outputs.emplace_back(static_cast<std::size_t>(n));
    if (n > 0) std::memcpy(v.data(), in.get_bytes(8 * v.size()).data(), 8 * v.size());
  }
  return p;
}

std::string to_bytes(const ChunkReport& r) {
  std::string out;
  put(out, r.index);
  put(out, r.rows);
  put(out, static_cast<std::uint32_t>(r.sizes.size()));
  for (std::size_t d = 0; d < r.sizes.size(); ++d) {
    put(out, r.sizes[d]);
    put(out, r.masks[d]);
  }
  put(out, static_cast<std::uint32_t>(r.summaries.size()));
  for (const ChunkSummary& s : r.summaries) put_summary(out, s);
  put(out, static_cast<std::uint32_t>(r.messages.size()));
  for (const auto& [row, text] : r.messages) {
    put(out, row);
    put(out, static_cast<std::uint32_t>(text.size()));
    out += text;
  }
  return out;
}

void read_chunk_report(std::string_view bytes, ChunkReport& r) {
  ByteReader in(bytes, "a chunk report");
  r.index = in.get<std::int64_t>();
  r.rows = in.get<std::int64_t>();
  const std::size_t n = get_count(in, 12, "a chunk report");
  r.sizes.resize(n);
  r.masks.resize(n);
  for (std::size_t d = 0; d < n; ++d) {
    r.sizes[d] = in.get<std::uint64_t>();
    r.masks[d] = in.get<std::uint32_t>();
  }
  r.summaries.resize(get_count(in, 1, "a chunk report"));
  for (ChunkSummary& s : r.summaries) get_summary(in, s);
  r.messages.resize(get_count(in, 12, "a chunk report"));
  for (auto& [row, text] : r.messages) {
    row = in.get<std::int64_t>();
    text.assign(in.get_bytes(get_count(in, 1, "a chunk report's message")));
  }
  in.expect_end();
}

std::string to_bytes(const ChunkPlacement& p) {
  std::string out;
  put(out, p.index);
  put(out, static_cast<std::uint32_t>(p.addresses.size()));
  for (const ChunkAddress& a : p.addresses) {
    put(out, a.offset);
    put(out, a.size);
  }
  put(out, static_cast<std::uint32_t>(p.windows.size()));
  for (const auto& w : p.windows) put_windows(out, w);
  return out;
}

ChunkPlacement read_chunk_placement(std::string_view bytes) {
  ByteReader in(bytes, "a chunk placement");
  ChunkPlacement p;
  p.index = in.get<std::int64_t>();
  p.addresses.resize(get_count(in, 16, "a chunk placement"));
  for (ChunkAddress& a : p.addresses) {
    a.offset = in.get<std::uint64_t>();
    a.size = in.get<std::uint64_t>();
  }
  p.windows.resize(get_count(in, 16 * kStatTargets, "a chunk placement"));
  for (auto& w : p.windows) get_windows(in, w);
  in.expect_end();
  return p;
}

}  // namespace truss::results
