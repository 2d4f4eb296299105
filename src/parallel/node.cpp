// A rank's messaging (engine_detail.hpp, Node) and the waits that keep serving it.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "parallel/engine_detail.hpp"
#include "parallel/interrupt.hpp"

namespace truss::parallel::detail {

namespace {
std::string& abort_removes() {
  static std::string path;  // the session's temporary results file, once every rank knows it
  return path;
}
}  // namespace

void set_abort_removes(const std::string& temporary) { abort_removes() = temporary; }

void abort_job(MPI_Comm comm, const char* where, const std::exception& e) {
  if (!abort_removes().empty()) ::unlink(abort_removes().c_str());
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::fprintf(stderr, "truss-campaign: fatal error on rank %d in %s: %s\n", rank, where, e.what());
  std::fflush(stderr);
  MPI_Abort(comm, 3);
  std::terminate();
}

void Backoff::sleep() {
  struct timespec ts{0, us_ * 1000};
  nanosleep(&ts, nullptr);
  us_ = std::min(us_ * 2, max_us_);
}

Node::Node(MPI_Comm comm, std::int64_t chunk_runs, std::size_t status_offset)
    : comm_(comm), chunk_runs_(chunk_runs), status_offset_(status_offset) {
  MPI_Comm_rank(comm, &rank_);
  MPI_Comm_size(comm, &size_);
}

void Node::set_rank0_chunks(std::vector<std::int64_t> chunks) {
  rank0_chunks_ = std::move(chunks);
  std::sort(rank0_chunks_.begin(), rank0_chunks_.end());
}

Node::~Node() = default;

int Node::owner_of(std::int64_t chunk) const {
  if (size_ == 1 || std::binary_search(rank0_chunks_.begin(), rank0_chunks_.end(), chunk)) return 0;
  return 1 + static_cast<int>(chunk % (size_ - 1));
}

void Node::send(int dest, int tag, std::string bytes) {
  if (dest == rank_) {
    local_.emplace_back(tag, std::move(bytes));
    return;
  }
  Out& o = sends_.emplace_back();
  o.bytes = std::move(bytes);
  o.records = tag == kTagRecords;
  if (o.records) record_bytes_ += o.bytes.size();
  // Timed as MPI time in a poll, but not in a handler (whose time is the owners' messages').
  const bool timed = in_poll_ && !in_handler_;
  const auto t0 = timed ? Clock::now() : Clock::time_point{};
  MPI_Isend(o.bytes.data(), static_cast<int>(o.bytes.size()), MPI_BYTE, dest, tag, comm_, &o.req);
  if (timed) mpi_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
}

void Node::route(std::string_view frame, std::int64_t run) {
  unsent_[owner_of(run / chunk_runs_)].append(frame);
  unsent_bytes_ += frame.size();
  if (unsent_bytes_ >= kRecordsMessageBytes) flush_records();
}

bool Node::has_unsent_records() const { return !unsent_.empty(); }

void Node::flush_records() {
  for (auto& [dest, bytes] : unsent_) send(dest, kTagRecords, std::move(bytes));
  unsent_.clear();
  unsent_bytes_ = 0;
}

// In the order they were posted, up to the first still in flight (sends complete about in order:
// testing every one at each poll costs more than the polls gain).
bool Node::test_sends() {
  bool any = false;
  while (!sends_.empty()) {
    int done = 0;
    MPI_Test(&sends_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) break;
    if (sends_.front().records) record_bytes_ -= sends_.front().bytes.size();
    sends_.pop_front();
    any = true;
  }
  return any;
}

// Every message that has arrived is matched and its receive posted at once, not when the rank
// needs it: a rendezvous message then moves while the rank computes.
bool Node::match() {
  if (!records_paused_) return match_one(MPI_ANY_TAG);
  bool any = false;
  for (int tag = kTagWork; tag <= kTagLast; ++tag)
    if (tag != kTagRecords) any |= match_one(tag);
  return any;
}

bool Node::match_one(int tag) {
  bool any = false;
  for (;;) {
    int flag = 0;
    MPI_Message m;
    MPI_Status st;
    MPI_Improbe(MPI_ANY_SOURCE, tag, comm_, &flag, &m, &st);
    if (!flag) return any;
    any = true;
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    In& in = received_.emplace_back();
    in.tag = st.MPI_TAG;
    in.source = st.MPI_SOURCE;
    in.bytes.resize(static_cast<std::size_t>(count));
    MPI_Imrecv(in.bytes.data(), count, MPI_BYTE, &m, &in.req);
  }
}

bool Node::poll_local() {
  bool any = false;
  while (!local_.empty()) {
    auto [tag, bytes] = std::move(local_.front());
    local_.pop_front();
    in_handler_ = true;
    handler_(tag, rank_, bytes);
    in_handler_ = false;
    any = true;
  }
  return any;
}

// Received messages as they complete, but a sender's messages of one kind in the order it sent
// them (a batch before the end of its round): a record message in flight from a rank busy with a
// run does not hold up the work behind it.
bool Node::handle_received() {
  bool any = false;
  std::vector<std::pair<int, int>> waiting;  // (source, tag) of a message still in flight
  for (auto it = received_.begin(); it != received_.end();) {
    const std::pair<int, int> key{it->source, it->tag};
    int done = 0;
    if (std::find(waiting.begin(), waiting.end(), key) == waiting.end()) {
      const auto t0 = Clock::now();
      MPI_Test(&it->req, &done, MPI_STATUS_IGNORE);
      mpi_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
    }
    if (!done) {
      waiting.push_back(key);
      ++it;
      continue;
    }
    In in = std::move(*it);
    it = received_.erase(it);
    in_handler_ = true;
    handler_(in.tag, in.source, in.bytes);
    in_handler_ = false;
    any = true;
  }
  return poll_local() || any;
}

bool Node::poll() {
  if (interrupted()) throw Interrupted();
  const auto t0 = Clock::now();
  in_poll_ = true;
  bool any = size_ > 1 && test_sends();
  if (size_ > 1) any |= match();
  mpi_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
  any |= handle_received();
  in_poll_ = false;
  poll_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
  return any;
}

void wait_serving(MPI_Request* req, Node& node, const std::function<bool()>& serve) {
  Backoff backoff;
  for (;;) {
    int done = 0;
    MPI_Test(req, &done, MPI_STATUS_IGNORE);
    if (done) return;
    const bool worked = node.poll() | serve();
    if (worked) backoff.reset();
    else backoff.sleep();
  }
}

}  // namespace truss::parallel::detail

namespace truss::parallel {

void wait_idle(MPI_Request* req) {
  detail::Backoff backoff;
  for (;;) {
    int done = 0;
    MPI_Test(req, &done, MPI_STATUS_IGNORE);
    if (done) return;
    backoff.sleep();
  }
}

int broadcast_int_idle(MPI_Comm comm, int v) {
  MPI_Request r;
  MPI_Ibcast(&v, 1, MPI_INT, 0, comm, &r);
  wait_idle(&r);
  return v;
}

}  // namespace truss::parallel
