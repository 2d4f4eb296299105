// The worker side of a round: batches in, their records out, never blocking while it holds work.
// Outstanding result sends are tested after every run, which is what moves a rendezvous message
// forward when the transport has no single-copy path (TCP, shared memory without CMA).
#include <cstdio>
#include <ctime>
#include <deque>
#include <list>
#include <stdexcept>

#include "parallel/engine_detail.hpp"
#include "util/bytes.hpp"

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

struct Message {
  std::string bytes;
  MPI_Request req = MPI_REQUEST_NULL;
};

class Worker {
 public:
  Worker(MPI_Comm comm, const methods::RoundPlan& plan, const Evaluate& evaluate)
      : comm_(comm), plan_(plan), evaluate_(evaluate) {}
  void run();

 private:
  void progress();  // after every run: tests sends, posts and completes work receives
  void test_sends();
  void post_work();      // MPI_Improbe + MPI_Imrecv of every work message that has arrived
  void complete_work();  // completed work receives (in order) become batches
  void compute_batch(const std::string& runs);

  MPI_Comm comm_;
  const methods::RoundPlan& plan_;
  const Evaluate& evaluate_;
  std::deque<std::string> batches_;  // run indices (i64 each); empty: the round is over
  std::deque<Message> posted_;       // work receives in flight, in arrival order (a deque: elements stay put)
  std::list<Message> sends_;         // a list: the buffers must not move while a send is in flight
  bool round_over_ = false;          // the end of the round is posted
};

void Worker::test_sends() {
  while (!sends_.empty()) {
    int done = 0;
    MPI_Test(&sends_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) return;
    sends_.pop_front();
  }
}

// A work message is received as soon as it is seen, not when the worker needs it; none after the
// end of the round (an empty one): the next round's batches may already be here.
void Worker::post_work() {
  while (!round_over_) {
    int flag = 0;
    MPI_Message m;
    MPI_Status st;
    MPI_Improbe(0, kTagWork, comm_, &flag, &m, &st);
    if (!flag) return;
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    Message& in = posted_.emplace_back();
    in.bytes.resize(static_cast<std::size_t>(count));
    MPI_Imrecv(in.bytes.data(), count, MPI_BYTE, &m, &in.req);
    round_over_ = count == 0;
  }
}

void Worker::complete_work() {
  while (!posted_.empty()) {
    int done = 0;
    MPI_Test(&posted_.front().req, &done, MPI_STATUS_IGNORE);
    if (!done) return;
    if (posted_.front().bytes.size() % 8 != 0)
      abort_job(comm_, "a work message", std::runtime_error("its size is not a whole number of run indices"));
    batches_.push_back(std::move(posted_.front().bytes));
    posted_.pop_front();
  }
}

void Worker::progress() {
  test_sends();
  post_work();
  complete_work();
}

void Worker::compute_batch(const std::string& runs) {
  std::string records;
  for (std::size_t at = 0; at < runs.size(); at += 8) {
    try {
      evaluate_(plan_, util::get_at<std::int64_t>(runs.data() + at), records);
    } catch (const std::exception& e) {
      abort_job(comm_, "a run", e);
    }
    progress();
  }
  Message& out = sends_.emplace_back();
  out.bytes = std::move(records);
  MPI_Isend(out.bytes.data(), static_cast<int>(out.bytes.size()), MPI_BYTE, 0, kTagResult, comm_, &out.req);
}

// Rank 0 sends two batches up front and one more per result message it matches, so the next batch
// is normally here already; it sends the end of the round once every result is in.
void Worker::run() {
  Backoff backoff;
  for (;;) {
    progress();
    if (batches_.empty()) {
      backoff.sleep();
      continue;
    }
    backoff.reset();
    const std::string runs = std::move(batches_.front());
    batches_.pop_front();
    if (runs.empty()) break;
    compute_batch(runs);
  }
  for (auto& s : sends_) wait_idle(&s.req);
}

}  // namespace

void run_worker_round(MPI_Comm comm, const methods::RoundPlan& plan, const Evaluate& evaluate) {
  Worker(comm, plan, evaluate).run();
}

}  // namespace truss::parallel::detail
