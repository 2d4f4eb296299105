// The worker side of the scheduler: batches in, framed results out, never blocking while it holds
// work. Outstanding result sends are tested after every run, which is what moves a rendezvous
// message forward when the transport has no single-copy path (TCP, shared memory without CMA).
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <deque>
#include <list>
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

class Worker {
 public:
  Worker(MPI_Comm comm, const ComputeFn& compute) : comm_(comm), compute_(compute) {}
  void run();

 private:
  void test_sends();       // progress: called after every run
  void receive_work();     // waits (sleeping) for at least one batch
  void compute_batch(const std::vector<std::int64_t>& batch);

  MPI_Comm comm_;
  const ComputeFn& compute_;
  std::deque<std::vector<std::int64_t>> batches_;
  std::list<Outgoing> sends_;  // a list: the buffers must not move while a send is in flight
  std::string one_;
};

void Worker::test_sends() {
  while (!sends_.empty()) {
    int done = 0;
    MPI_Test(&sends_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) return;
    sends_.pop_front();
  }
}

// Rank 0 sends two batches up front and one more per result message it matches, so the next
// batch is normally here already. Work messages are received with a matched probe: once matched,
// rank 0 (which tests its sends between runs) completes them within one of its runs.
void Worker::receive_work() {
  Backoff backoff;
  for (;;) {
    int flag = 0;
    MPI_Message m;
    MPI_Status st;
    MPI_Improbe(0, kTagWork, comm_, &flag, &m, &st);
    if (flag) {
      int count = 0;
      MPI_Get_count(&st, MPI_INT64_T, &count);
      std::vector<std::int64_t> b(static_cast<std::size_t>(count));
      MPI_Request r;
      MPI_Imrecv(b.data(), count, MPI_INT64_T, &m, &r);
      int done = 0;
      while (!done) {
        MPI_Test(&r, &done, MPI_STATUS_IGNORE);
        if (!done) {
          test_sends();
          backoff.sleep();
        }
      }
      batches_.push_back(std::move(b));
      return;
    }
    test_sends();
    backoff.sleep();
  }
}

void Worker::compute_batch(const std::vector<std::int64_t>& batch) {
  std::string bytes;
  for (std::int64_t run : batch) {
    one_.clear();
    try {
      compute_(run, one_);
    } catch (const std::exception& e) {
      abort_job(comm_, "a run", e);
    }
    append_framed(bytes, one_);
    test_sends();
  }
  Outgoing& out = sends_.emplace_back();
  out.bytes = std::move(bytes);
  MPI_Isend(out.bytes.data(), static_cast<int>(out.bytes.size()), MPI_BYTE, 0, kTagResult, comm_, &out.req);
}

void Worker::run() {
  for (;;) {
    if (batches_.empty()) receive_work();
    const std::vector<std::int64_t> batch = std::move(batches_.front());
    batches_.pop_front();
    if (batch.empty()) break;  // the stop message: rank 0 sends it after every batch
    compute_batch(batch);
  }
  for (auto& s : sends_) wait_idle(&s.req);
}

}  // namespace

void run_worker(MPI_Comm comm, const ComputeFn& compute) { Worker(comm, compute).run(); }

}  // namespace truss::parallel::detail
