// A rank's chunks of runs (chunk_builder.hpp).
#include "results/chunk_builder.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "util/bytes.hpp"

namespace truss::results {

using campaign::Field;
using campaign::RecordLayout;
using campaign::ValueType;

std::string StoreOptions::validate() const {
  if (chunk_runs < 1) return fmt::format("chunk_runs: must be >= 1, got {}", chunk_runs);
  if (deflate_level < 0 || deflate_level > 9)
    return fmt::format("deflate_level: must be 0 to 9, got {}", deflate_level);
  return {};
}

std::int64_t find_chunk_runs(std::int64_t n_runs) {
  const std::int64_t rows = std::clamp<std::int64_t>(n_runs / 8, 1024, 4096);
  return std::max<std::int64_t>(1, std::min(rows, n_runs));
}

ChunkColumns::ChunkColumns(const RecordLayout& layout) {
  const auto& fields = layout.fields();
  for (std::size_t f = 0; f < fields.size(); ++f) {
    ChunkColumn c{static_cast<int>(f), campaign::value_bytes(fields[f].type),
                  static_cast<std::size_t>(fields[f].width)};
    if (fields[f].statistics) {
      c.stats = static_cast<int>(n_stats);
      n_stats += c.width;
    }
    columns.push_back(c);
  }
  columns.push_back({ChunkColumn::kSession, 8, 1, -1});
}

// A chunk of runs in memory, until every row has arrived and it is encoded: each record's fields
// scattered on arrival into the chunk's column blocks, one per field (field f's block at
// chunk_runs x f.offset, its row i at i x f.bytes()).
struct ChunkBuilder::Chunk {
  std::int64_t index = 0, filled = 0;
  std::unique_ptr<char[]> cols;  // chunk_runs x fixed_bytes, by field
  std::vector<std::string> message;
  std::vector<std::int64_t> session;
  std::vector<std::uint8_t> use;   // ok runs (status 0): they feed the statistics
  std::vector<std::uint8_t> have;  // rows in
  std::map<std::int64_t, std::int64_t> round_rows;  // rows in, by round
  bool queued = false;             // in complete_
};

ChunkBuilder::ChunkBuilder(const RecordLayout& layout, const StoreOptions& opts, std::vector<std::size_t> observed)
    : L_(layout), cols_(layout), chunk_(opts.chunk_runs), deflate_(opts.deflate_level), observed_(std::move(observed)) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("chunk builder: " + e);
}

ChunkBuilder::~ChunkBuilder() = default;

void ChunkBuilder::add_round(std::int64_t round, std::int64_t first_run, std::int64_t n_runs) {
  if (round < static_cast<std::int64_t>(rounds_.size())) {  // known already (restored): the same round
    const Round& r = rounds_[static_cast<std::size_t>(round)];
    if (r.first == first_run && r.end == first_run + n_runs) return;
  }
  if (ended_ || round != static_cast<std::int64_t>(rounds_.size()) || first_run != planned_ || n_runs < 0)
    throw std::logic_error(fmt::format("chunk builder: round {} (runs {} to {}) after runs 0 to {}", round, first_run,
                                       first_run + n_runs - 1, planned_ - 1));
  rounds_.push_back({round, first_run, first_run + n_runs});
  planned_ = first_run + n_runs;
}

void ChunkBuilder::end_rounds() {
  ended_ = true;
  for (auto& [k, c] : open_) check_complete(*c);
}

std::int64_t ChunkBuilder::rows_of(std::int64_t chunk) const {
  return std::clamp<std::int64_t>(planned_ - chunk * chunk_, 0, chunk_);
}

// All its rows are in: a full chunk, or the last one once no round follows.
bool ChunkBuilder::complete(const Chunk& c) const {
  const std::int64_t rows = rows_of(c.index);
  return c.filled == rows && (rows == chunk_ || ended_);
}

void ChunkBuilder::check_complete(Chunk& c) {
  if (c.queued || c.filled == 0 || !complete(c)) return;
  c.queued = true;
  complete_.push_back(c.index);
}

ChunkBuilder::Chunk& ChunkBuilder::chunk_for(std::int64_t run) {
  const std::int64_t k = run / chunk_;
  if (const auto it = open_.find(k); it != open_.end()) return *it->second;
  auto c = std::make_unique<Chunk>();
  const auto n = static_cast<std::size_t>(chunk_);
  c->index = k;
  c->cols = std::make_unique_for_overwrite<char[]>(n * L_.fixed_bytes());
  c->message.resize(n);
  c->session.resize(n);
  c->use.resize(n);
  c->have.resize(n);
  Chunk& ref = *c;
  open_.emplace(k, std::move(c));
  peak_chunks_ = std::max(peak_chunks_, open_.size());
  return ref;
}

void ChunkBuilder::check(const campaign::RecordView& rec) const {
  const std::int64_t run = rec.run(), round = rec.round();
  const Round* r = round >= 0 && round < static_cast<std::int64_t>(rounds_.size())
                       ? &rounds_[static_cast<std::size_t>(round)] : nullptr;  // rounds are 0, 1, ... in order
  if (!r || run < r->first || run >= r->end)
    throw std::runtime_error(fmt::format("a record of run {} in round {}, which is not one of its runs", run, round));
  const std::int64_t k = run / chunk_;
  const auto it = open_.find(k);
  if ((static_cast<std::size_t>(k) < encoded_.size() && encoded_[static_cast<std::size_t>(k)]) ||
      (it != open_.end() && it->second->have[static_cast<std::size_t>(run - k * chunk_)]))
    throw std::runtime_error(fmt::format("run {} received twice", run));
}

void ChunkBuilder::add(const campaign::RecordView& rec, std::int64_t session) {
  check(rec);
  const std::int64_t run = rec.run(), round = rec.round();
  const Round* r = &rounds_[static_cast<std::size_t>(round)];
  Chunk& c = chunk_for(run);
  const auto i = static_cast<std::size_t>(run - c.index * chunk_);
  c.have[i] = 1;
  const char* src = rec.bytes().data();
  char* cols = c.cols.get();
  const auto rows = static_cast<std::size_t>(chunk_);
  for (const Field& f : L_.fields()) {
    const std::size_t bytes = f.bytes();
    std::memcpy(cols + rows * f.offset + i * bytes, src + f.offset, bytes);
  }
  c.message[i].assign(rec.message());
  c.session[i] = session;
  c.use[i] = rec.status() == 0;
  ++c.filled;
  const std::int64_t lo = std::max(r->first, c.index * chunk_), hi = std::min(r->end, (c.index + 1) * chunk_);
  if (++c.round_rows[round] == hi - lo) push_part(c, *r);
  check_complete(c);
}

// Rows lo .. hi - 1 of round r, all in chunk c: their statuses and observed outputs.
void ChunkBuilder::push_part(Chunk& c, const Round& r) {
  const std::int64_t lo = std::max(r.first, c.index * chunk_), hi = std::min(r.end, (c.index + 1) * chunk_);
  RoundPart p;
  p.round = r.round;
  p.first_run = lo;
  const auto rows = static_cast<std::size_t>(chunk_);
  const auto at = [&](std::size_t field, std::int64_t run) {
    return c.cols.get() + rows * L_.fields()[field].offset + static_cast<std::size_t>(run - c.index * chunk_) *
                                                                 L_.fields()[field].bytes();
  };
  for (std::int64_t run = lo; run < hi; ++run)
    p.status.push_back(static_cast<std::int8_t>(*at(RecordLayout::kStatus, run)));
  for (std::size_t f : observed_) {
    auto& v = p.outputs.emplace_back();
    for (std::int64_t run = lo; run < hi; ++run) v.push_back(util::get_at<double>(at(f, run)));
  }
  parts_.push_back(std::move(p));
}

std::optional<RoundPart> ChunkBuilder::pop_part() {
  if (parts_.empty()) return std::nullopt;
  RoundPart p = std::move(parts_.front());
  parts_.pop_front();
  return p;
}

std::optional<std::int64_t> ChunkBuilder::pop_complete() {
  if (complete_.empty()) return std::nullopt;
  const std::int64_t k = complete_.front();
  complete_.pop_front();
  return k;
}

bool ChunkBuilder::encode_step(std::int64_t chunk, const std::vector<statistics::Windows>& windows, EncodedChunk& out) {
  const auto it = open_.find(chunk);
  if (it == open_.end() || !complete(*it->second))
    throw std::logic_error(fmt::format("chunk {} is not complete", chunk));
  Chunk& c = *it->second;
  const std::size_t d = out.bytes.size();
  if (d == 0) {
    out.report = {};
    out.report.index = chunk;
    out.report.rows = rows_of(chunk);
    out.report.summaries.resize(cols_.n_stats);
  }
  const ChunkColumn& col = cols_.columns[d];
  const std::size_t bytes = col.width * col.elem, n = static_cast<std::size_t>(chunk_);
  const auto r = static_cast<std::size_t>(out.report.rows);
  char* block = col.field == ChunkColumn::kSession
                    ? reinterpret_cast<char*>(c.session.data())
                    : c.cols.get() + n * L_.fields()[static_cast<std::size_t>(col.field)].offset;
  std::memset(block + r * bytes, 0, (n - r) * bytes);  // the rows past the last run of a partial chunk
  std::string& enc = out.bytes.emplace_back();
  out.report.masks.push_back(codec_.encode({block, n * bytes}, col.elem, deflate_, enc));
  out.report.sizes.push_back(enc.size());
  if (col.stats >= 0) summarize(c, col, block, windows, out);
  if (out.bytes.size() < cols_.columns.size()) return false;
  for (std::size_t i = 0; i < r; ++i)
    if (!c.message[i].empty()) out.report.messages.emplace_back(static_cast<std::int64_t>(i), std::move(c.message[i]));
  if (encoded_.size() <= static_cast<std::size_t>(chunk)) encoded_.resize(static_cast<std::size_t>(chunk) + 1, false);
  encoded_[static_cast<std::size_t>(chunk)] = true;
  open_.erase(it);
  return true;
}

void ChunkBuilder::summarize(const Chunk& c, const ChunkColumn& col, const char* block,
                             const std::vector<statistics::Windows>& windows, EncodedChunk& out) {
  const auto rows = static_cast<std::size_t>(out.report.rows);
  for (std::size_t b = 0; b < col.width; ++b) {
    const auto k = static_cast<std::size_t>(col.stats) + b;
    statistics::calc_chunk_summary(block + 8 * b, rows, col.width, c.use.data(), windows.at(k),
                                   out.report.summaries[k]);
  }
}

std::vector<std::int64_t> ChunkBuilder::open_indices() const {
  std::vector<std::int64_t> k;
  for (const auto& [index, c] : open_) k.push_back(index);
  return k;
}

std::vector<statistics::Windows> ChunkBuilder::first_windows(std::int64_t chunk) const {
  return first_windows(chunk, {0, cols_.n_stats});
}

std::vector<statistics::Windows> ChunkBuilder::first_windows(std::int64_t chunk, ColumnRange columns) const {
  const Chunk& c = *open_.at(chunk);
  const auto rows = static_cast<std::size_t>(rows_of(chunk)), n = static_cast<std::size_t>(chunk_);
  std::vector<statistics::Windows> w;
  for (const ChunkColumn& col : cols_.columns) {
    if (col.stats < 0) continue;
    const char* block = c.cols.get() + n * L_.fields()[static_cast<std::size_t>(col.field)].offset;
    for (std::size_t b = 0; b < col.width; ++b) {
      const std::size_t k = static_cast<std::size_t>(col.stats) + b;
      if (k >= columns.begin && k < columns.end)
        w.push_back(statistics::calc_first_windows(block + 8 * b, rows, col.width, c.use.data()));
    }
  }
  return w;
}

}  // namespace truss::results
