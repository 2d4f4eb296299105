// The round loop on every rank, and rank 0's side of a round's schedule (the worker's is in
// worker.cpp).
#include "parallel/engine.hpp"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <exception>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "parallel/engine_detail.hpp"
#include "util/bytes.hpp"

namespace truss::parallel {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Adds the wall time of its scope to a counter (steady clock).
class ScopeTimer {
 public:
  explicit ScopeTimer(double& sum) : sum_(sum) {}
  ~ScopeTimer() { sum_ += seconds_since(t0_); }
  ScopeTimer(const ScopeTimer&) = delete;
  ScopeTimer& operator=(const ScopeTimer&) = delete;

 private:
  double& sum_;
  Clock::time_point t0_ = Clock::now();
};

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Rank 0's fatal error: the results file's temporary name removed (the journal keeps every finished
// run for --resume), then the job aborted.
[[noreturn]] void abort_rank0(MPI_Comm comm, Collector& collector, const char* where, const std::exception& e) {
  collector.remove_temporary_file();
  abort_job(comm, where, e);
}

// A worker's result message, received into memory of its own.
struct Incoming {
  std::string bytes;
  MPI_Request req = MPI_REQUEST_NULL;
};

// Rank 0 in one round: hands out the round's runs in index order in guided batches, computes one
// run at a time itself, and between its runs matches the workers' result messages (answering each
// at once with the next batch), stores the results and writes the chunks they completed.
class Rank0Round {
 public:
  Rank0Round(MPI_Comm comm, const methods::RoundPlan& plan, Collector& collector, const Evaluate& evaluate,
             const EngineOptions& opts, results::ScheduleSummary& sum);
  void run();
  double compute_cpu_s() const { return compute_cpu_s_; }

 private:
  void send_batch(int w);
  std::int64_t next_run();  // the next run of the round not in the results yet
  bool poll();
  bool match_new();
  bool complete_receives();
  void test_sends();
  void compute_one();
  void maybe_tick();

  MPI_Comm comm_;
  const methods::RoundPlan& plan_;
  Collector& collector_;
  const results::ResultStore& store_;
  const Evaluate& evaluate_;
  const EngineOptions& opts_;
  results::ScheduleSummary& sum_;
  int size_ = 1;
  std::int64_t cursor_, to_do_ = 0, handed_ = 0, received_ = 0;
  std::vector<std::uint8_t> waiting_;
  std::vector<std::unique_ptr<Incoming>> incoming_;  // receives in flight (parallel to recv_reqs_)
  std::vector<MPI_Request> recv_reqs_;
  std::vector<std::unique_ptr<std::string>> sends_;  // work messages in flight (parallel to send_reqs_)
  std::vector<MPI_Request> send_reqs_;
  std::vector<int> done_idx_;
  std::string one_;
  Clock::time_point last_tick_ = Clock::now();
  double compute_cpu_s_ = 0.0;
};

// Drops the entries whose requests MPI_Testsome completed (set to MPI_REQUEST_NULL) from two
// parallel vectors, keeping the order of the rest.
template <class T>
void drop_completed(std::vector<MPI_Request>& reqs, std::vector<T>& items) {
  std::size_t w = 0;
  for (std::size_t i = 0; i < reqs.size(); ++i) {
    if (reqs[i] == MPI_REQUEST_NULL) continue;
    reqs[w] = reqs[i];
    items[w] = std::move(items[i]);
    ++w;
  }
  reqs.resize(w);
  items.resize(w);
}

Rank0Round::Rank0Round(MPI_Comm comm, const methods::RoundPlan& plan, Collector& collector, const Evaluate& evaluate,
                       const EngineOptions& opts, results::ScheduleSummary& sum)
    : comm_(comm), plan_(plan), collector_(collector), store_(collector.store()), evaluate_(evaluate), opts_(opts),
      sum_(sum), cursor_(plan.first_run) {
  MPI_Comm_size(comm, &size_);
  waiting_.assign(static_cast<std::size_t>(size_), 0);
  for (std::int64_t i = plan.first_run; i < plan.end_run(); ++i) to_do_ += !store_.has(i);  // --resume: some are in
}

std::int64_t Rank0Round::next_run() {
  while (store_.has(cursor_)) ++cursor_;
  ++handed_;
  return cursor_++;
}

// Guided batches: remaining / (batches_per_rank * ranks), at least 1, at most max_batch. A worker
// that asks when no run is left waits for the end of the round.
void Rank0Round::send_batch(int w) {
  const std::int64_t remaining = to_do_ - handed_;
  std::int64_t k = remaining / (std::int64_t{opts_.batches_per_rank} * size_);
  k = std::min(std::clamp<std::int64_t>(k, 1, opts_.max_batch), remaining);
  if (k == 0) {
    waiting_[static_cast<std::size_t>(w)] = 1;
    return;
  }
  auto out = std::make_unique<std::string>();
  for (std::int64_t i = 0; i < k; ++i) util::put(*out, next_run());
  ScopeTimer t(sum_.rank0_mpi_s);
  MPI_Request r;
  MPI_Isend(out->data(), static_cast<int>(out->size()), MPI_BYTE, w, kTagWork, comm_, &r);
  send_reqs_.push_back(r);
  sends_.push_back(std::move(out));
}

bool Rank0Round::match_new() {
  bool any = false;
  for (;;) {
    int flag = 0;
    MPI_Message m;
    MPI_Status st;
    {
      ScopeTimer t(sum_.rank0_mpi_s);
      MPI_Improbe(MPI_ANY_SOURCE, kTagResult, comm_, &flag, &m, &st);
    }
    if (!flag) return any;
    any = true;
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    auto in = std::make_unique<Incoming>();
    in->bytes.resize(static_cast<std::size_t>(count));
    {
      ScopeTimer t(sum_.rank0_mpi_s);
      MPI_Imrecv(in->bytes.data(), count, MPI_BYTE, &m, &in->req);
    }
    recv_reqs_.push_back(in->req);
    incoming_.push_back(std::move(in));
    // The worker has finished a batch and started the one it held: send its next one now, not
    // when the data has arrived.
    send_batch(st.MPI_SOURCE);
  }
}

bool Rank0Round::complete_receives() {
  if (recv_reqs_.empty()) return false;
  int n_done = 0;
  done_idx_.resize(recv_reqs_.size());
  {
    ScopeTimer t(sum_.rank0_mpi_s);
    MPI_Testsome(static_cast<int>(recv_reqs_.size()), recv_reqs_.data(), &n_done, done_idx_.data(),
                 MPI_STATUSES_IGNORE);
  }
  if (n_done <= 0) return false;
  ScopeTimer t(sum_.rank0_result_s);
  for (int k = 0; k < n_done; ++k) {
    std::string_view msg = incoming_[static_cast<std::size_t>(done_idx_[static_cast<std::size_t>(k)])]->bytes;
    try {
      while (!msg.empty()) {
        const std::string_view frame = results::read_frame(msg).bytes;
        collector_.add_frame(frame, plan_);
        msg.remove_prefix(frame.size());
        ++received_;
        ++sum_.runs_by_workers;
      }
    } catch (const std::exception& e) {
      abort_rank0(comm_, collector_, "storing results", e);
    }
  }
  drop_completed(recv_reqs_, incoming_);
  return true;
}

void Rank0Round::test_sends() {
  if (send_reqs_.empty()) return;
  int n_done = 0;
  done_idx_.resize(send_reqs_.size());
  {
    ScopeTimer t(sum_.rank0_mpi_s);
    MPI_Testsome(static_cast<int>(send_reqs_.size()), send_reqs_.data(), &n_done, done_idx_.data(),
                 MPI_STATUSES_IGNORE);
  }
  if (n_done > 0) drop_completed(send_reqs_, sends_);
}

bool Rank0Round::poll() {
  ScopeTimer t(sum_.rank0_poll_s);
  const bool matched = match_new();
  const bool received = complete_receives();
  test_sends();
  return matched || received;
}

// Rank 0 takes single runs from the same pool, so it is never more than one run late in
// answering a worker.
void Rank0Round::compute_one() {
  const std::int64_t run = next_run();
  one_.clear();
  const auto t0 = Clock::now();
  const double c0 = thread_cpu_s();
  try {
    evaluate_(plan_, run, one_);
  } catch (const std::exception& e) {
    abort_rank0(comm_, collector_, "a run", e);
  }
  compute_cpu_s_ += thread_cpu_s() - c0;
  sum_.rank0_compute_s += seconds_since(t0);
  ++sum_.runs_by_rank0;
  ScopeTimer tp(sum_.rank0_poll_s), tr(sum_.rank0_result_s);
  try {
    collector_.add_frame(one_, plan_);
  } catch (const std::exception& e) {
    abort_rank0(comm_, collector_, "storing a result", e);
  }
  ++received_;
}

void Rank0Round::maybe_tick() {
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_tick_).count() < opts_.tick_interval_s) return;
  last_tick_ = now;
  try {
    collector_.tick(false);
  } catch (const std::exception& e) {
    abort_rank0(comm_, collector_, "syncing the journal", e);
  }
  sum_.rank0_tick_s += seconds_since(now);
}

// Until every result of the round is in: answer and store, write a complete chunk's next dataset
// if one waits, else compute a run, else wait a little. Then every worker gets the end of the round.
void Rank0Round::run() {
  {
    ScopeTimer t(sum_.rank0_poll_s);  // answering: inside rank0_poll_s, as every send
    for (int w = 1; w < size_; ++w) send_batch(w);
    for (int w = 1; w < size_; ++w)
      if (!waiting_[static_cast<std::size_t>(w)]) send_batch(w);
  }
  Backoff backoff(200);  // rank 0 idles only at the end of a round, where latency matters
  while (received_ < to_do_) {
    const bool progressed = poll();
    if (collector_.write_pending()) {
      ScopeTimer t(sum_.rank0_write_s);
      try {
        collector_.write_next();
      } catch (const std::exception& e) {
        abort_rank0(comm_, collector_, "writing the results file", e);
      }
    } else if (handed_ < to_do_) {
      compute_one();
    } else if (!progressed) {
      ScopeTimer t(sum_.rank0_idle_s);
      backoff.sleep();
    } else {
      backoff.reset();
    }
    maybe_tick();
  }
  ScopeTimer t(sum_.rank0_poll_s);
  for (int w = 1; w < size_; ++w) {  // the end of the round: an empty work message
    send_reqs_.emplace_back();
    MPI_Isend(nullptr, 0, MPI_BYTE, w, kTagWork, comm_, &send_reqs_.back());
  }
  for (MPI_Request& r : send_reqs_) wait_idle(&r);
  sends_.clear();
  send_reqs_.clear();
}

// Round r's plan from rank 0 to every rank: its size, then its bytes.
methods::RoundPlan broadcast_plan(MPI_Comm comm, const methods::RoundPlan& plan, bool root) {
  std::string bytes = root ? plan.to_bytes() : std::string();
  long long n = static_cast<long long>(bytes.size());
  MPI_Request r;
  MPI_Ibcast(&n, 1, MPI_LONG_LONG, 0, comm, &r);
  wait_idle(&r);
  bytes.resize(static_cast<std::size_t>(n));
  MPI_Ibcast(bytes.data(), static_cast<int>(n), MPI_BYTE, 0, comm, &r);
  wait_idle(&r);
  return root ? plan : methods::RoundPlan::from_bytes(bytes);
}

}  // namespace

std::string EngineOptions::validate() const {
  if (max_batch < 1) return fmt::format("max_batch: must be >= 1, got {}", max_batch);
  if (batches_per_rank < 1) return fmt::format("batches_per_rank: must be >= 1, got {}", batches_per_rank);
  if (!(tick_interval_s > 0.0)) return fmt::format("tick_interval_s: must be positive, got {}", tick_interval_s);
  if (!(flush_interval_s > 0.0)) return fmt::format("flush_interval_s: must be positive, got {}", flush_interval_s);
  return {};
}

EngineResult run_engine(MPI_Comm comm, const Evaluate& evaluate, Collector* collector, const EngineOptions& opts) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("engine options: " + e);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const bool root = rank == 0;
  EngineResult out;
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_s();
  double compute_cpu = 0.0;
  std::int64_t first = 0;
  for (std::int64_t r = 0;; ++r) {
    methods::RoundPlan plan;
    if (root) {
      try {
        plan = collector->plan_round(r, first);
      } catch (const std::exception& e) {
        abort_rank0(comm, *collector, "planning a round", e);
      }
    }
    plan = broadcast_plan(comm, plan, root);
    if (plan.n_runs == 0) break;
    out.plans.push_back(plan);
    if (root) {
      Rank0Round round(comm, plan, *collector, evaluate, opts, out.schedule);
      round.run();
      compute_cpu += round.compute_cpu_s();
    } else {
      run_worker_round(comm, plan, evaluate);
    }
    first = plan.end_run();
  }
  if (root) {
    out.schedule.schedule_wall_s = seconds_since(t0);
    out.schedule.rank0_compute_cpu_s = compute_cpu;
    out.schedule.rank0_handle_cpu_s = thread_cpu_s() - cpu0 - compute_cpu;
  }
  return out;
}

void wait_idle(MPI_Request* req) {
  Backoff backoff;
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
