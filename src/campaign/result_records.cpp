// Records into the chunk buffers (result_store.hpp): checked and counted on rank 0's thread
// (accept), copied into their chunk's column buffers where the chunks live (store_record: on the
// write thread when there is one, so that the thread answering the workers only checks, counts and
// hands over). add_bytes stages copies (its bytes live in the caller's buffer); add_records hands
// over views into a received message that the task keeps alive.
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/result_store.hpp"
#include "campaign/result_store_parts.hpp"
#include "campaign/store_jobs.hpp"

namespace truss::campaign {

ResultStore::Chunk& ResultStore::chunk_for(std::int64_t run) {
  const std::int64_t k = run / chunk_;
  auto it = open_.find(k);
  if (it != open_.end()) return *it->second;
  std::unique_ptr<Chunk> c;
  if (!spare_.empty()) {
    c = std::move(spare_.back());
    spare_.pop_back();
  } else {
    c = std::make_unique<Chunk>();
  }
  const Datasets& d = *ds_;
  c->first = k * chunk_;
  c->rows = std::min(chunk_, n_ - c->first);
  c->filled = 0;
  const auto full = static_cast<std::size_t>(std::min(chunk_, n_));
  c->buf.resize(d.direct.size());
  for (std::size_t j = 0; j < d.direct.size(); ++j) {
    const std::size_t bytes = kJobHeader + full * d.direct[j].width * d.direct[j].elem;
    // Room for the statistics request (append_request) and the job's carrier, so that neither
    // copies the chunk again.
    const std::size_t room = bytes + 8 + full + d.direct[j].width * sizeof(Windows) + headroom_;
    std::string& b = c->buf[j];
    if (b.capacity() < room) {
      std::lock_guard<std::mutex> lock(jobs_m_);
      b = pool_.take(room);
    }
    if (b.size() >= bytes && c->rows == chunk_) b.resize(bytes);  // every row of a full chunk is overwritten
    else b.assign(bytes, '\0');  // an edge chunk: zeros past n
  }
  c->message.assign(static_cast<std::size_t>(c->rows), {});
  Chunk& ref = *c;
  open_.emplace(k, std::move(c));
  peak_chunks_ = std::max(peak_chunks_, open_.size());
  return ref;
}

void ResultStore::add(const RunRecord& r, int session) {
  std::string bytes;
  r.append_bytes(bytes);
  add_bytes(bytes, session);
}

namespace {
constexpr std::size_t kStageBytes = std::size_t{1} << 16;  // records staged for the write thread: about 14 of 4.4 kB
}  // namespace

void ResultStore::add_bytes(std::string_view rec, int session) {
  accept(rec);
  if (!writes_) {
    store_record(rec, session);
    return;
  }
  const std::uint32_t head[2] = {static_cast<std::uint32_t>(rec.size()), static_cast<std::uint32_t>(session)};
  if (staged_.capacity() < kStageBytes + rec.size() + sizeof head) staged_.reserve(kStageBytes + rec.size() + sizeof head);
  staged_.append(reinterpret_cast<const char*>(head), sizeof head);
  staged_.append(rec);
  ++staged_n_;
  if (staged_.size() >= kStageBytes) post_staged();
}

void ResultStore::add_records(std::shared_ptr<const char[]> owner, const std::vector<std::string_view>& views,
                              std::size_t skip, int session) {
  std::size_t bytes = 0;
  for (std::string_view v : views) {
    if (v.size() < skip) throw std::runtime_error(fmt::format("a result of {} bytes holds no record", v.size()));
    accept(v.substr(skip));
    bytes += v.size();
  }
  if (!writes_) {
    for (std::string_view v : views) store_record(v.substr(skip), session);
    return;
  }
  if (views.empty()) return;
  post_staged();
  records_posted_ += static_cast<std::int64_t>(views.size());
  writes_->post(
      [this, owner = std::move(owner), views, skip, session] {
        for (std::string_view v : views) store_record(v.substr(skip), session);
        records_stored_ += static_cast<std::int64_t>(views.size());
      },
      bytes);
}

void ResultStore::post_staged() {
  if (!writes_ || staged_.empty()) return;
  const auto n = staged_n_;
  records_posted_ += n;
  const std::size_t bytes = staged_.size();
  writes_->post(
      [this, recs = std::move(staged_), n] {
        for (std::size_t at = 0; at < recs.size();) {
          std::uint32_t head[2];
          std::memcpy(head, recs.data() + at, sizeof head);
          store_record(std::string_view(recs).substr(at + sizeof head, head[0]), static_cast<std::int32_t>(head[1]));
          at += sizeof head + head[0];
        }
        records_stored_ += n;
      },
      bytes);
  staged_ = std::string();
  staged_n_ = 0;
}

bool ResultStore::jobs_pending() {
  post_staged();
  if (writes_ && records_stored_.load() < records_posted_) return true;
  std::lock_guard<std::mutex> lock(jobs_m_);
  return !jobs_.empty();
}

// The record layout of RunRecord::append_bytes: i64 run, i8 status, i32 rank, f64 wall time,
// u32 message length and message, then the f64, i64, per-bay and input arrays.
void ResultStore::accept(std::string_view rec) {
  const OutputColumns& cols = ctx_.columns;
  const RecordHead h = rec.size() >= kRecordHead ? read_record_head(rec) : RecordHead{};
  const std::int64_t run = h.run;
  const std::uint32_t len = h.message_bytes;
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
  const std::size_t values = cols.f64.size() + cols.i64.size() + cols.bay.size() * nb + static_cast<std::size_t>(cols.n_inputs);
  if (rec.size() < kRecordHead || rec.size() != kRecordHead + len + 4 * 4 + 8 * values)
    throw std::runtime_error(fmt::format("a record of {} bytes is not a run record of this campaign", rec.size()));
  // Each array is prefixed by its length (u32): checked against the columns.
  const std::size_t counts[4] = {cols.f64.size(), cols.i64.size(), cols.bay.size() * nb, static_cast<std::size_t>(cols.n_inputs)};
  for (std::size_t k = 0, at = kRecordHead + len; k < 4; at += 4 + 8 * counts[k], ++k) {
    std::uint32_t m = 0;
    std::memcpy(&m, rec.data() + at, 4);
    if (m != counts[k]) throw std::runtime_error(fmt::format("record has {} values where {} are expected", m, counts[k]));
  }
  const std::int8_t status = h.status;
  if (status < 0 || status >= sim::kRunStatusCount) throw std::runtime_error(fmt::format("record has an unknown status {}", status));
  if (run < 0 || run >= n_) throw std::runtime_error(fmt::format("run index {} out of range", run));
  if (done_[static_cast<std::size_t>(run)]) throw std::runtime_error(fmt::format("run {} received twice", run));
  done_[static_cast<std::size_t>(run)] = 1;
  ++n_done_;
  if (status != 0) ++n_failed_;
  ++status_counts_[static_cast<std::size_t>(status)];
}

// A record that accept() has passed, copied into its chunk's column buffers.
void ResultStore::store_record(std::string_view rec, int session) {
  const OutputColumns& cols = ctx_.columns;
  const Datasets& d = *ds_;
  const RecordHead h = read_record_head(rec);
  const std::int64_t run = h.run;
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
  Chunk& c = chunk_for(run);
  const auto i = static_cast<std::size_t>(run - c.first);
  auto put = [&](std::size_t ds, const void* src, std::size_t bytes) {
    std::memcpy(c.buf[ds].data() + kJobHeader + i * bytes, src, bytes);
  };
  const std::int64_t rank64 = h.rank, session64 = session;
  put(0, &run, 8);
  put(1, &h.status, 1);
  put(2, rec.data() + kRecordWall, 8);
  put(3, &rank64, 8);
  put(4, &session64, 8);
  c.message[i].assign(rec.data() + kRecordHead, h.message_bytes);
  const char* p = rec.data() + kRecordHead + h.message_bytes + 4;
  for (std::size_t k = 0; k < cols.f64.size(); ++k, p += 8) put(d.f64_0 + k, p, 8);
  p += 4;
  for (std::size_t k = 0; k < cols.i64.size(); ++k, p += 8) put(d.i64_0 + k, p, 8);
  p += 4;
  for (std::size_t k = 0; k < cols.bay.size(); ++k, p += 8 * nb) put(d.bays_0 + k, p, 8 * nb);
  p += 4;
  const DimensionLayout& L = ctx_.sampler.layout();
  for (std::size_t k = 0; k < L.count.size(); ++k)
    put(d.inputs_0 + k, p + 8 * static_cast<std::size_t>(L.offset[k]), 8 * static_cast<std::size_t>(L.count[k]));
  if (++c.filled < c.rows) return;
  complete_chunk(c);
  auto it = open_.find(c.first / chunk_);
  spare_.push_back(std::move(it->second));
  open_.erase(it);
  if (spare_.size() > 2) spare_.resize(2);
}
}  // namespace truss::campaign
