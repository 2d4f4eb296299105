// The statistics read back by any rank (read_back.hpp): the jobs' shares, the answers applied, and
// the messages. Reading and computing are read_columns.cpp's.
#include "results/read_back.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "util/bytes.hpp"

namespace truss::results {

std::uint64_t ReadBackJob::stored_bytes() const {
  std::uint64_t b = 0;
  for (const Chunk& c : chunks) b += c.bytes;
  return b;
}

void apply_read_back(StreamedStats& s, const std::vector<ReadBackAnswer>& answers) {
  for (const ReadBackAnswer& a : answers) {
    const auto i = static_cast<std::size_t>(a.index);
    if (a.group < 0) {
      s.f64.at(i).percentiles = a.percentiles;
      s.f64_resolved.at(i) = 1;
    } else {
      s.bays.at(static_cast<std::size_t>(a.group)).at(i).percentiles = a.percentiles;
      s.bays_resolved.at(static_cast<std::size_t>(a.group)).at(i) = 1;
    }
    ++s.read_back;
  }
}

std::vector<std::size_t> find_jobs_of(const std::vector<ReadBackJob>& jobs, int rank, int size) {
  std::vector<std::size_t> order(jobs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return jobs[a].stored_bytes() > jobs[b].stored_bytes(); });
  std::vector<std::uint64_t> load(static_cast<std::size_t>(std::max(size, 1)), 0);
  std::vector<std::size_t> mine;
  for (const std::size_t j : order) {
    const auto r = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    load[r] += jobs[j].stored_bytes();
    if (static_cast<int>(r) == rank) mine.push_back(j);
  }
  return mine;
}

namespace {

void put_string(std::string& out, std::string_view s) {
  util::put(out, static_cast<std::uint64_t>(s.size()));
  out += s;
}

std::string_view get_string(util::ByteReader& in) {
  const auto n = in.get<std::uint64_t>();
  if (n > in.left()) throw std::runtime_error("a read-back plan: a string longer than its message");
  return in.get_bytes(static_cast<std::size_t>(n));
}

std::size_t get_count(util::ByteReader& in, std::size_t item_bytes) {
  const auto n = in.get<std::uint64_t>();
  if (n > in.left() / std::max<std::size_t>(item_bytes, 1))
    throw std::runtime_error(fmt::format("a read-back message: {} items announced, {} bytes left", n, in.left()));
  return static_cast<std::size_t>(n);
}

}  // namespace

// path, ok (u64 n, n bytes), u64 jobs, each: path, i64 rows, chunk_rows, width, u8 filtered,
// u64 chunks x (u64 offset, u64 bytes, u32 mask), u64 columns x (i64 column, i32 group, i64 index).
std::string to_bytes(const ReadBackPlan& p) {
  std::string out;
  put_string(out, p.path);
  put_string(out, std::string_view(reinterpret_cast<const char*>(p.ok.data()), p.ok.size()));
  util::put(out, static_cast<std::uint64_t>(p.jobs.size()));
  for (const ReadBackJob& j : p.jobs) {
    put_string(out, j.path);
    for (std::int64_t v : {j.rows, j.chunk_rows, j.width}) util::put(out, v);
    util::put(out, static_cast<std::uint8_t>(j.filtered));
    util::put(out, static_cast<std::uint64_t>(j.chunks.size()));
    for (const auto& c : j.chunks) {
      util::put(out, c.offset);
      util::put(out, c.bytes);
      util::put(out, c.mask);
    }
    util::put(out, static_cast<std::uint64_t>(j.columns.size()));
    for (const auto& c : j.columns) {
      util::put(out, c.column);
      util::put(out, c.group);
      util::put(out, c.index);
    }
  }
  return out;
}

ReadBackPlan read_read_back_plan(std::string_view bytes) {
  util::ByteReader in(bytes, "a read-back plan");
  ReadBackPlan p;
  p.path = std::string(get_string(in));
  const std::string_view ok = get_string(in);
  p.ok.assign(ok.begin(), ok.end());
  p.jobs.resize(get_count(in, 41));
  for (ReadBackJob& j : p.jobs) {
    j.path = std::string(get_string(in));
    for (std::int64_t* v : {&j.rows, &j.chunk_rows, &j.width}) *v = in.get<std::int64_t>();
    j.filtered = in.get<std::uint8_t>() != 0;
    j.chunks.resize(get_count(in, 20));
    for (auto& c : j.chunks) {
      c.offset = in.get<std::uint64_t>();
      c.bytes = in.get<std::uint64_t>();
      c.mask = in.get<std::uint32_t>();
    }
    j.columns.resize(get_count(in, 20));
    for (auto& c : j.columns) {
      c.column = in.get<std::int64_t>();
      c.group = in.get<std::int32_t>();
      c.index = in.get<std::int64_t>();
    }
    if (j.rows < 0 || j.chunk_rows < 1 || j.width < 1 ||
        static_cast<std::int64_t>(j.chunks.size()) != (j.rows + j.chunk_rows - 1) / j.chunk_rows)
      throw std::runtime_error(fmt::format("a read-back plan: {} chunks for {} rows of {}", j.chunks.size(), j.rows,
                                           j.chunk_rows));
    for (const auto& c : j.columns)
      if (c.column < 0 || c.column >= j.width)
        throw std::runtime_error(fmt::format("a read-back plan: column {} of {}", c.column, j.width));
  }
  in.expect_end();
  return p;
}

// u64 n, n x (i32 group, i64 index, the percentiles).
std::string to_bytes(const std::vector<ReadBackAnswer>& a) {
  std::string out;
  util::put(out, static_cast<std::uint64_t>(a.size()));
  for (const ReadBackAnswer& x : a) {
    util::put(out, x.group);
    util::put(out, x.index);
    for (double v : x.percentiles) util::put(out, v);
  }
  return out;
}

std::vector<ReadBackAnswer> read_read_back_answers(std::string_view bytes) {
  util::ByteReader in(bytes, "read-back answers");
  std::vector<ReadBackAnswer> a(get_count(in, 12 + 8 * statistics::kStatTargets));
  for (ReadBackAnswer& x : a) {
    x.group = in.get<std::int32_t>();
    x.index = in.get<std::int64_t>();
    for (double& v : x.percentiles) v = in.get<double>();
  }
  in.expect_end();
  return a;
}

}  // namespace truss::results
