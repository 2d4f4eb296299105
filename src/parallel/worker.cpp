// The worker side of a round: batches in, their records to their chunks' owners, never blocking
// while it holds work. The rank's messages are served after every run (node.poll: what moves a
// rendezvous message forward when the transport has no single-copy path), and its chunks' work is
// paced by its runs (Worker::compute_one).
#include <stdexcept>

#include "parallel/engine_detail.hpp"
#include "util/bytes.hpp"

namespace truss::parallel::detail {

namespace {

// A rank encoding a chunk runs at a third of its speed at worst. On 2 ranks the one owner of every
// chunk spends about a third of its time on Table-1 chunks: with a share of one, not two, its last
// chunks were left for the end of the campaign (docs/benchmarks.md, "A sweep's rounds").
constexpr double kChunkTimePerRunTime = 2.0;

class Worker {
 public:
  Worker(Node& node, WorkQueue& work, const methods::RoundPlan& plan, const Evaluate& evaluate,
         const std::function<bool(double)>& serve)
      : node_(node), work_(work), plan_(plan), evaluate_(evaluate), serve_(serve) {}
  void run();

 private:
  void compute_batch(const std::string& ranges);
  void compute_one(std::int64_t run, results::StatusCounts& counts);
  void wait_for_sends();

  Node& node_;
  WorkQueue& work_;
  const methods::RoundPlan& plan_;
  const Evaluate& evaluate_;
  const std::function<bool(double)>& serve_;
  std::string frame_;
  double chunk_credit_s_ = 0.0;  // the chunk work the rank's runs have paid for (compute_one)
};

// While too many of its records are in flight, a rank serves and waits: its owners are behind.
void Worker::wait_for_sends() {
  Backoff backoff;
  while (node_.flow_blocked()) {
    if (node_.poll() | serve_(kServeSliceS)) backoff.reset();
    else backoff.sleep();
  }
}

// A round ends with its slowest rank's last run, and a worker holds up to two batches sized by rank
// 0's pace. So the rank's chunks get, after each run, at most kChunkTimePerRunTime times the wall
// time the run took (credit carried over: one step of their work may outlast a run), and none once
// rank 0 has said that the round's runs are all handed out: then it runs what it holds back to back
// and does the chunks' work once it holds none. (With a fixed millisecond after each run, a rank
// encoding a chunk, about 30 ms of work for 2,000 motor runs, ran its runs at a tenth of their
// speed, and a sweep's rounds waited tens of milliseconds for it.) A rank whose owners fall behind
// serves them in wait_for_sends.
void Worker::compute_one(std::int64_t run, results::StatusCounts& counts) {
  wait_for_sends();
  const auto t0 = Clock::now();
  frame_.clear();
  try {
    evaluate_(plan_, run, frame_);
  } catch (const std::exception& e) {
    abort_job(node_.comm(), "a run", e);
  }
  node_.route(frame_, run);
  const auto status = static_cast<std::int8_t>(frame_[node_.status_at()]);
  if (status < 0 || status >= sim::kRunStatusCount)
    abort_job(node_.comm(), "a run", std::runtime_error("its record's status is out of range"));
  ++counts[static_cast<std::size_t>(status)];
  node_.poll();
  if (work_.drained(plan_.round)) return;
  chunk_credit_s_ = std::min(chunk_credit_s_ + kChunkTimePerRunTime * seconds_since(t0), kServeSliceS);
  if (chunk_credit_s_ <= 0.0) return;
  const auto t1 = Clock::now();
  serve_(chunk_credit_s_);
  chunk_credit_s_ -= seconds_since(t1);
}

// A batch: its ranges' runs, their records to their owners, then its status counts to rank 0 (the
// progress; one message a batch, which also asks for the next).
void Worker::compute_batch(const std::string& ranges) {
  if (ranges.size() % 16 != 0)
    abort_job(node_.comm(), "a work message", std::runtime_error("its size is not a whole number of run ranges"));
  results::StatusCounts counts{};
  for (std::size_t at = 0; at < ranges.size(); at += 16) {
    const auto first = util::get_at<std::int64_t>(ranges.data() + at);
    const auto n = util::get_at<std::int64_t>(ranges.data() + at + 8);
    if (n < 1 || !plan_.contains(first) || !plan_.contains(first + n - 1))
      abort_job(node_.comm(), "a work message", std::runtime_error("a range of runs outside its round"));
    for (std::int64_t run = first; run < first + n; ++run) compute_one(run, counts);
  }
  node_.flush_records();
  std::string done;
  util::put(done, counts);
  node_.send(0, kTagDone, std::move(done));
}

// Rank 0 sends two batches up front and one more per batch done, so the next batch is normally
// here already; it sends the end of the round once every record of the round is in.
void Worker::run() {
  Backoff backoff;
  for (;;) {
    const bool progressed = node_.poll();
    if (work_.empty()) {
      if (progressed | serve_(kServeSliceS)) backoff.reset();
      else backoff.sleep();
      continue;
    }
    backoff.reset();
    const std::string runs = work_.pop();
    if (runs.empty()) break;
    compute_batch(runs);
  }
}

}  // namespace

void run_worker_round(Node& node, WorkQueue& work, const methods::RoundPlan& plan, const Evaluate& evaluate,
                      const std::function<bool(double)>& serve) {
  Worker(node, work, plan, evaluate, serve).run();
}

}  // namespace truss::parallel::detail
