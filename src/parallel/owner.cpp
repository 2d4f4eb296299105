// A rank's chunks (owner.hpp).
#include "parallel/owner.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <iterator>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "parallel/engine_detail.hpp"
#include "results/chunk_messages.hpp"

namespace truss::parallel {

using namespace detail;

ChunkOwner::ChunkOwner(const campaign::RecordLayout& layout, const results::StoreOptions& opts,
                       std::vector<std::size_t> observed, OwnerFiles files, Send send, double flush_interval_s)
    : builder_(layout, opts, std::move(observed)), files_(std::move(files)), send_(std::move(send)),
      flush_interval_s_(flush_interval_s) {}

ChunkOwner::~ChunkOwner() {
  if (data_fd_ >= 0) ::close(data_fd_);
}

void ChunkOwner::add_round(const methods::RoundPlan& plan) {
  builder_.add_round(plan.round, plan.first_run, plan.n_runs);
  std::vector<std::string> w;
  w.swap(waiting_);
  for (const std::string& frames : w) add_records(frames);
}

void ChunkOwner::end_rounds() {
  if (!waiting_.empty())
    throw std::runtime_error(fmt::format("records of a round that was never planned ({} bytes)", waiting_[0].size()));
  ended_ = true;
  builder_.end_rounds();
}

void ChunkOwner::journal(std::string_view frames) {
  if (files_.rank != 0 && !part_)
    part_ = std::make_unique<results::Journal>(results::Journal::create_part(
        results::part_journal_path(files_.output, files_.session, files_.rank), files_.campaign_crc, files_.session,
        files_.rank));
  (part_ ? *part_ : *files_.journal).append_frame(frames);
}

// Each frame checked (a record of a round planned here, of a run not in yet) before the journal
// takes it: a duplicate never reaches a journal.
void ChunkOwner::add_records(std::string_view frames) {
  const campaign::RecordLayout& L = builder_.layout();
  std::string_view rest = frames;
  while (!rest.empty()) {
    const results::Frame f = results::read_frame(rest);
    if (f.kind != results::FrameKind::run)
      throw std::runtime_error("a result message holds a frame that is not a run's");
    if (const std::string e = L.check(f.payload); !e.empty()) throw std::runtime_error(e);
    const campaign::RecordView rec(f.payload, L);
    if (rec.round() >= builder_.rounds()) {  // its plan has not reached this rank yet
      waiting_.emplace_back(rest);
      return;
    }
    builder_.check(rec);
    journal(f.bytes);
    builder_.add(rec, files_.session);
    rest.remove_prefix(f.bytes.size());
  }
}

void ChunkOwner::replay_record(std::string_view record, std::int64_t session) {
  builder_.add(campaign::RecordView(record, builder_.layout()), session);
}

bool ChunkOwner::send_parts() {
  bool written = false;
  while (auto p = builder_.pop_part()) {
    if (!written) {  // the records of the part survive the process before rank 0 hears of it
      if (part_ || files_.rank == 0) (part_ ? *part_ : *files_.journal).write_out();
      written = true;
    }
    send_(0, kTagPart, results::to_bytes(*p));
  }
  return written;
}

bool ChunkOwner::start_encoding() {
  while (auto k = builder_.pop_complete()) to_encode_.push_back(*k);
  if (encoding_ || to_encode_.empty()) return false;
  if (windows_missing_ != 0) {  // the first windows come from the statistics ranks
    if (windows_missing_ > 0) return false;
    windows_.resize(builder_.columns().n_stats);
    windows_missing_ = files_.stats.count;
    for (int s = 0; s < files_.stats.count; ++s) send_(files_.stats.first + s, kTagAskWindows, {});
    return true;
  }
  encoding_ = to_encode_.front();
  to_encode_.pop_front();
  encoded_ = {};
  return true;
}

bool ChunkOwner::step() {
  const bool sent = send_parts() | start_encoding();
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_sync_).count() >= flush_interval_s_) {
    if (part_) part_->flush();
    // The chunks' bytes go to disk during the run, not in the tail; advisory (a file system
    // without sync_file_range only leaves more for finish()'s fdatasync).
    if (data_fd_ >= 0) (void)::sync_file_range(data_fd_, 0, 0, SYNC_FILE_RANGE_WRITE);
    last_sync_ = now;
  }
  if (!encoding_) return sent;
  if (builder_.encode_step(*encoding_, windows_, encoded_)) {
    results::ChunkReport& r = encoded_.report;
    // Each statistics rank's part of the report: its columns' summaries.
    const std::size_t n_stats = r.summaries.size();
    for (int rank = files_.stats.first; rank < files_.stats.first + files_.stats.count; ++rank) {
      const results::ColumnRange c = files_.stats.find_columns(rank, n_stats);
      results::ChunkReport summaries;
      summaries.index = r.index;
      summaries.rows = r.rows;
      summaries.summaries.assign(std::make_move_iterator(r.summaries.begin() + static_cast<std::ptrdiff_t>(c.begin)),
                                 std::make_move_iterator(r.summaries.begin() + static_cast<std::ptrdiff_t>(c.end)));
      send_(rank, kTagSummary, results::to_bytes(summaries));
    }
    r.summaries.clear();
    send_(0, kTagChunk, results::to_bytes(r));
    placing_.emplace(*encoding_, std::move(encoded_));
    encoding_.reset();
  }
  return true;
}

void ChunkOwner::on_windows(int source, std::string_view bytes) {
  std::vector<statistics::Windows> w = results::read_chunk_placement(bytes).windows;
  if (!files_.stats.holds(source)) throw std::runtime_error(fmt::format("windows from rank {}", source));
  const results::ColumnRange c = files_.stats.find_columns(source, windows_.size());
  if (w.size() != c.size())
    throw std::runtime_error(fmt::format("windows of {} columns from rank {} for {}", w.size(), source, c.size()));
  std::copy(w.begin(), w.end(), windows_.begin() + static_cast<std::ptrdiff_t>(c.begin));
  if (windows_missing_ > 0) --windows_missing_;  // its first: each rank answers the ask once
}

void ChunkOwner::on_seed_ask(int source) {
  if (to_encode_.empty()) throw std::logic_error("asked for the first windows without a complete chunk");
  results::ChunkPlacement p;
  p.index = -1;
  p.windows = builder_.first_windows(to_encode_.front(), files_.stats.find_columns(source, builder_.columns().n_stats));
  send_(source, kTagSeed, results::to_bytes(p));
}

void ChunkOwner::on_placement(std::string_view bytes) {
  write_chunk(results::read_chunk_placement(bytes));
}

void ChunkOwner::write_chunk(const results::ChunkPlacement& p) {
  const auto it = placing_.find(p.index);
  if (it == placing_.end() || it->second.bytes.size() != p.addresses.size())
    throw std::runtime_error(fmt::format("a placement of chunk {}, which this rank did not report", p.index));
  if (data_fd_ < 0) data_fd_ = ::open(files_.temporary.c_str(), O_WRONLY | O_CLOEXEC);
  if (data_fd_ < 0)
    throw std::runtime_error(
        fmt::format("cannot open the results file {}: {}", files_.temporary, std::strerror(errno)));
  for (std::size_t d = 0; d < p.addresses.size(); ++d) {
    const std::string& b = it->second.bytes[d];
    if (p.addresses[d].size != b.size())
      throw std::runtime_error(fmt::format("chunk {}: placed {} bytes for {}", p.index, p.addresses[d].size, b.size()));
    std::size_t at = 0;
    while (at < b.size()) {
      const auto where = static_cast<off_t>(p.addresses[d].offset + at);
      const ssize_t n = ::pwrite(data_fd_, b.data() + at, b.size() - at, where);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0)
        throw std::runtime_error(fmt::format("cannot write chunk {} into {}: {}", p.index, files_.temporary,
                                             std::strerror(errno)));
      at += static_cast<std::size_t>(n);
    }
  }
  placing_.erase(it);
}

bool ChunkOwner::done() const {
  return ended_ && waiting_.empty() && builder_.open_chunks() == 0 && !encoding_ && to_encode_.empty() &&
         placing_.empty();
}

void ChunkOwner::finish() {
  if (data_fd_ >= 0) {
    if (::fdatasync(data_fd_) != 0 || ::close(data_fd_) != 0) {
      data_fd_ = -1;
      throw std::runtime_error(fmt::format("cannot sync the results file {}: {}", files_.temporary,
                                           std::strerror(errno)));
    }
    data_fd_ = -1;
  }
  if (part_) part_->flush();
}

void ChunkOwner::write_out_journal() {
  try {
    if (part_) part_->write_out();
  } catch (...) {
  }
}

std::vector<std::int64_t> ChunkOwner::open_chunks() const { return builder_.open_indices(); }

}  // namespace truss::parallel
