// The worker side of the scheduler: batches in, framed results out, never blocking while it holds
// work. Outstanding result sends are tested after every run, which is what moves a rendezvous
// message forward when the transport has no single-copy path (TCP, shared memory without CMA).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <deque>
#include <list>
#include <stdexcept>
#include <vector>

#include "parallel/scheduler_detail.hpp"

namespace truss::parallel::detail {

void abort_job(MPI_Comm comm, const char* where, const std::exception& e) {
  std::fprintf(stderr, "truss-campaign: fatal error in %s: %s\n", where, e.what());
  std::fflush(stderr);
  MPI_Abort(comm, 3);
  std::terminate();
}

void Backoff::sleep() {
  struct timespec ts{0, us_ * 1000};
  nanosleep(&ts, nullptr);
  us_ = std::min(us_ * 2, max_us_);
}

namespace {

struct Outgoing {
  std::string bytes;
  MPI_Request req = MPI_REQUEST_NULL;
};

struct Batch {
  std::vector<std::int64_t> runs;
  std::string message;       // the work message: its first job_bytes are a side job to run first
  std::size_t job_bytes = 0;
};

class Worker {
 public:
  Worker(MPI_Comm comm, const ComputeFn& compute, const ScheduleOptions& opts) : comm_(comm), compute_(compute), opts_(opts) {}
  void run();

 private:
  void progress();         // called after every run: tests sends, posts and completes work receives
  void test_sends();
  void post_work();        // MPI_Improbe + MPI_Imrecv of every work message that has arrived
  void complete_work();    // completed work receives (in order) become batches
  void receive_work();     // waits (sleeping) for at least one batch
  void compute_batch(const Batch& batch);

  MPI_Comm comm_;
  const ComputeFn& compute_;
  const ScheduleOptions& opts_;
  std::deque<Batch> batches_;
  std::deque<Outgoing> posted_;  // work receives in flight, in arrival order (a deque: elements stay put)
  std::list<Outgoing> sends_;    // a list: the buffers must not move while a send is in flight
  std::string one_, job_out_;
};

void Worker::test_sends() {
  while (!sends_.empty()) {
    int done = 0;
    MPI_Test(&sends_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) return;
    sends_.pop_front();
  }
}

// A work message is received as soon as it is seen, not when the worker needs it: a large one
// (with a side job) then moves while the worker computes, with rank 0 progressing it between its runs.
void Worker::post_work() {
  for (;;) {
    int flag = 0;
    MPI_Message m;
    MPI_Status st;
    MPI_Improbe(0, kTagWork, comm_, &flag, &m, &st);
    if (!flag) return;
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    Outgoing& in = posted_.emplace_back();
    in.bytes.resize(static_cast<std::size_t>(count));
    MPI_Imrecv(in.bytes.data(), count, MPI_BYTE, &m, &in.req);
  }
}

void Worker::complete_work() {
  while (!posted_.empty()) {
    int done = 0;
    MPI_Test(&posted_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) return;
    std::string& b = posted_.front().bytes;
    std::uint32_t trailer[2] = {0, 0};
    if (b.size() < kWorkTrailer) abort_job(comm_, "a work message", std::runtime_error("shorter than its trailer"));
    std::memcpy(trailer, b.data() + b.size() - kWorkTrailer, kWorkTrailer);
    if (std::size_t{trailer[1]} + 8 * std::size_t{trailer[0]} + kWorkTrailer != b.size())
      abort_job(comm_, "a work message", std::runtime_error("its trailer does not match its size"));
    Batch& batch = batches_.emplace_back();
    batch.runs.resize(trailer[0]);
    if (trailer[0] > 0) std::memcpy(batch.runs.data(), b.data() + trailer[1], 8 * std::size_t{trailer[0]});
    batch.job_bytes = trailer[1];
    batch.message = std::move(b);
    posted_.pop_front();
  }
}

void Worker::progress() {
  test_sends();
  post_work();
  complete_work();
}

// Rank 0 sends two batches up front and one more per result message it matches, so the next
// batch is normally here already.
void Worker::receive_work() {
  Backoff backoff;
  for (;;) {
    progress();
    if (!batches_.empty()) return;
    backoff.sleep();
  }
}

void Worker::compute_batch(const Batch& batch) {
  job_out_.clear();
  if (batch.job_bytes > 0) {
    try {
      opts_.do_job(std::string_view(batch.message).substr(0, batch.job_bytes), job_out_);
    } catch (const std::exception& e) {
      abort_job(comm_, "a side job", e);
    }
  }
  std::string bytes;
  const auto job = static_cast<std::uint32_t>(job_out_.size());
  bytes.append(reinterpret_cast<const char*>(&job), sizeof job);
  bytes += job_out_;
  for (std::int64_t run : batch.runs) {
    one_.clear();
    try {
      compute_(run, one_);
    } catch (const std::exception& e) {
      abort_job(comm_, "a run", e);
    }
    append_framed(bytes, one_);
    progress();
  }
  Outgoing& out = sends_.emplace_back();
  out.bytes = std::move(bytes);
  MPI_Isend(out.bytes.data(), static_cast<int>(out.bytes.size()), MPI_BYTE, 0, kTagResult, comm_, &out.req);
}

void Worker::run() {
  for (;;) {
    if (batches_.empty()) receive_work();
    const Batch batch = std::move(batches_.front());
    batches_.pop_front();
    if (batch.runs.empty() && batch.job_bytes == 0) break;  // the stop message: rank 0 sends it last
    compute_batch(batch);
  }
  for (auto& s : sends_) wait_idle(&s.req);
}

}  // namespace

void run_worker(MPI_Comm comm, const ComputeFn& compute, const ScheduleOptions& opts) { Worker(comm, compute, opts).run(); }

}  // namespace truss::parallel::detail
