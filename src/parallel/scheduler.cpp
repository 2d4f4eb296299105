// Rank 0's side of the scheduler (the worker's is in scheduler_worker.cpp).
#include "parallel/scheduler.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <ctime>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "parallel/scheduler_detail.hpp"

namespace truss::parallel {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Adds the wall time of its scope to a counter (steady clock, about 20 ns a read here).
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

struct Incoming {
  int source = 0;
  std::shared_ptr<char[]> bytes;  // not zeroed: MPI writes every byte (and on_message may keep it)
  std::size_t size = 0;
};
struct WorkOut {
  std::string bytes;  // kTagWork layout
  bool job = false;   // bytes is a side job's buffer (handed back through on_job_sent)
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

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

class Rank0 {
 public:
  Rank0(MPI_Comm comm, const std::vector<std::int64_t>& todo, const ComputeFn& compute, const ResultFn& on_result,
        const TickFn& on_tick, const ScheduleOptions& opts);
  ScheduleSummary run();

 private:
  void send_batch(int w);
  bool poll();              // matches, receives and answers; true if anything happened
  bool match_new();         // MPI_Improbe every waiting result message, MPI_Imrecv it, answer its sender
  bool complete_receives();
  void test_sends();
  void deliver(std::string_view one);
  void compute_one();
  void maybe_tick();
  void dispatch_waiting();
  void job_sent(WorkOut& s) {
    if (s.job && opts_.on_job_sent) opts_.on_job_sent(std::move(s.bytes));
  }

  MPI_Comm comm_;
  const std::vector<std::int64_t>& todo_;
  const ComputeFn& compute_;
  const ResultFn& on_result_;
  const TickFn& on_tick_;
  const ScheduleOptions& opts_;
  int size_ = 1;
  std::size_t next_run_ = 0;  // todo_[next_run_] is the next run to hand out
  std::int64_t received_ = 0;
  std::vector<std::uint8_t> stopped_, waiting_;
  bool final_ = false;         // sending stop messages: no more jobs
  std::int64_t jobs_out_ = 0;  // side jobs sent whose output has not come back
  std::vector<MPI_Request> recv_reqs_;              // parallel to incoming_
  std::vector<std::unique_ptr<Incoming>> incoming_;  // buffers stay put while their receive is posted
  // Sends in flight and their requests, in parallel: one MPI_Testsome tests them all. An MPI_Test
  // per send would run the progress engine once per pending send (up to two per worker at P ranks).
  std::vector<std::unique_ptr<WorkOut>> sends_;
  std::vector<MPI_Request> send_reqs_;
  std::int64_t n_waiting_ = 0;  // workers with waiting_ set
  std::vector<int> done_idx_;
  std::vector<std::string_view> views_;  // the results of one message (on_message)
  std::string one_, job_;
  Clock::time_point last_tick_ = Clock::now();
  ScheduleSummary sum_;
  double compute_cpu_s_ = 0.0;  // rank 0's thread CPU time inside compute()
  double local_jobs_cpu_ = 0.0;  // ... and in side jobs it ran itself while idle (not per-result work)
  bool local_job() {
    if (!opts_.do_local_job) return false;
    const double c0 = thread_cpu_s();
    const bool did = opts_.do_local_job();
    local_jobs_cpu_ += thread_cpu_s() - c0;
    return did;
  }
};

Rank0::Rank0(MPI_Comm comm, const std::vector<std::int64_t>& todo, const ComputeFn& compute, const ResultFn& on_result,
             const TickFn& on_tick, const ScheduleOptions& opts)
    : comm_(comm), todo_(todo), compute_(compute), on_result_(on_result), on_tick_(on_tick), opts_(opts) {
  MPI_Comm_size(comm, &size_);
  stopped_.assign(static_cast<std::size_t>(size_), 0);
  waiting_.assign(static_cast<std::size_t>(size_), 0);
}

// Workers with no runs left to do get the side jobs that have appeared since they asked (at the
// end: the encoding of the last chunk).
void Rank0::dispatch_waiting() {
  if (!opts_.take_job || n_waiting_ == 0) return;
  for (int w = 1; w < size_; ++w)
    if (waiting_[static_cast<std::size_t>(w)] && !stopped_[static_cast<std::size_t>(w)]) send_batch(w);
}

// Guided batches: remaining / (batches_per_rank * ranks), at least 1, at most max_batch. An empty
// batch is the stop message.
void Rank0::send_batch(int w) {
  auto out = std::make_unique<WorkOut>();
  const std::size_t remaining = todo_.size() - next_run_;
  std::size_t k = remaining / static_cast<std::size_t>(opts_.batches_per_rank * size_);
  k = std::min(std::clamp<std::size_t>(k, 1, static_cast<std::size_t>(opts_.max_batch)), remaining);
  job_.clear();
  const bool job = !final_ && opts_.take_job && opts_.take_job(job_);
  if (!job) job_.clear();
  if (k == 0 && !job && !final_) {  // nothing to do now: it waits, and gets a job or the stop message later
    if (!waiting_[static_cast<std::size_t>(w)]) ++n_waiting_;
    waiting_[static_cast<std::size_t>(w)] = 1;
    return;
  }
  if (waiting_[static_cast<std::size_t>(w)]) --n_waiting_;
  waiting_[static_cast<std::size_t>(w)] = 0;
  if (job) {
    ++sum_.jobs_sent;
    ++jobs_out_;
  }
  // The job's own buffer becomes the message: the runs and the trailer are appended to it.
  const std::uint32_t trailer[2] = {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(job_.size())};
  out->job = job;
  out->bytes = std::move(job_);
  job_ = std::string();
  out->bytes.append(reinterpret_cast<const char*>(todo_.data() + next_run_), 8 * k);
  out->bytes.append(reinterpret_cast<const char*>(trailer), sizeof trailer);
  next_run_ += k;
  if (k == 0 && !job) stopped_[static_cast<std::size_t>(w)] = 1;
  {
    ScopeTimer t(sum_.rank0_mpi_s);
    MPI_Request r;
    MPI_Isend(out->bytes.data(), static_cast<int>(out->bytes.size()), MPI_BYTE, w, kTagWork, comm_, &r);
    send_reqs_.push_back(r);
  }
  sends_.push_back(std::move(out));
  ++sum_.batches_sent;
}

bool Rank0::match_new() {
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
    in->source = st.MPI_SOURCE;
    in->size = static_cast<std::size_t>(count);
    in->bytes = std::make_shared_for_overwrite<char[]>(in->size);
    MPI_Request r;
    {
      ScopeTimer t(sum_.rank0_mpi_s);
      MPI_Imrecv(in->bytes.get(), count, MPI_BYTE, &m, &r);
    }
    recv_reqs_.push_back(r);
    incoming_.push_back(std::move(in));
    sum_.bytes_received += count;
    // The worker has finished a batch and started the one it held: send its next one now, not
    // when the data has arrived.
    if (!stopped_[static_cast<std::size_t>(st.MPI_SOURCE)]) send_batch(st.MPI_SOURCE);
  }
}

bool Rank0::complete_receives() {
  if (recv_reqs_.empty()) return false;
  int n_done = 0;
  done_idx_.resize(recv_reqs_.size());
  {
    ScopeTimer t(sum_.rank0_mpi_s);
    MPI_Testsome(static_cast<int>(recv_reqs_.size()), recv_reqs_.data(), &n_done, done_idx_.data(), MPI_STATUSES_IGNORE);
  }
  if (n_done <= 0) return false;
  for (int k = 0; k < n_done; ++k) {
    const auto before = received_;
    Incoming& in = *incoming_[static_cast<std::size_t>(done_idx_[static_cast<std::size_t>(k)])];
    const std::string_view msg(in.bytes.get(), in.size);
    std::uint32_t job = 0;
    std::memcpy(&job, msg.data(), sizeof job);
    if (job > 0) {
      --jobs_out_;
      try {
        ScopeTimer t(sum_.rank0_job_output_s);
        opts_.on_job_done(in.bytes, in.size, msg.substr(sizeof job, job));
      } catch (const std::exception& e) {
        abort_job(comm_, "storing a side job's output", e);
      }
    }
    if (opts_.on_message) {
      views_.clear();
      for_each_framed(msg.substr(sizeof job + job), [&](std::string_view one) { views_.push_back(one); });
      try {
        ScopeTimer t(sum_.rank0_result_s);
        opts_.on_message(std::move(in.bytes), views_);
      } catch (const std::exception& e) {
        abort_job(comm_, "storing results", e);
      }
      received_ += static_cast<std::int64_t>(views_.size());
    } else {
      for_each_framed(msg.substr(sizeof job + job), [&](std::string_view one) { deliver(one); });
    }
    sum_.runs_by_workers += received_ - before;
  }
  drop_completed(recv_reqs_, incoming_);
  return true;
}

void Rank0::test_sends() {
  if (send_reqs_.empty()) return;
  int n_done = 0;
  done_idx_.resize(send_reqs_.size());
  {
    ScopeTimer t(sum_.rank0_mpi_s);
    MPI_Testsome(static_cast<int>(send_reqs_.size()), send_reqs_.data(), &n_done, done_idx_.data(), MPI_STATUSES_IGNORE);
  }
  if (n_done <= 0) return;
  for (int k = 0; k < n_done; ++k) job_sent(*sends_[static_cast<std::size_t>(done_idx_[static_cast<std::size_t>(k)])]);
  drop_completed(send_reqs_, sends_);
}

bool Rank0::poll() {
  ScopeTimer t(sum_.rank0_poll_s);
  const bool matched = match_new();
  const bool received = complete_receives();
  test_sends();
  dispatch_waiting();
  return matched || received;
}

void Rank0::deliver(std::string_view one) {
  try {
    ScopeTimer t(sum_.rank0_result_s);
    on_result_(one);
  } catch (const std::exception& e) {
    abort_job(comm_, "storing a result", e);
  }
  ++received_;
}

// Rank 0 takes single runs from the same pool, so it is never more than one run late in
// answering a worker.
void Rank0::compute_one() {
  const std::int64_t run = todo_[next_run_++];
  one_.clear();
  const auto t0 = Clock::now();
  const double c0 = thread_cpu_s();
  try {
    compute_(run, one_);
  } catch (const std::exception& e) {
    abort_job(comm_, "a run", e);
  }
  compute_cpu_s_ += thread_cpu_s() - c0;
  sum_.rank0_compute_s += seconds_since(t0);
  ++sum_.runs_by_rank0;
  const auto t1 = Clock::now();
  deliver(one_);
  sum_.rank0_poll_s += seconds_since(t1);
}

void Rank0::maybe_tick() {
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_tick_).count() < opts_.tick_interval_s) return;
  last_tick_ = now;
  on_tick_();
  sum_.rank0_tick_s += seconds_since(now);
}

ScheduleSummary Rank0::run() {
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_s();
  const auto total = static_cast<std::int64_t>(todo_.size());
  {
    ScopeTimer t(sum_.rank0_poll_s);  // answering: inside rank0_poll_s, as every send
    for (int w = 1; w < size_; ++w) send_batch(w);
    for (int w = 1; w < size_; ++w)
      if (!stopped_[static_cast<std::size_t>(w)]) send_batch(w);
  }
  if (opts_.on_started) opts_.on_started();
  Backoff backoff(200);  // rank 0 idles only at the very end, where latency matters
  double handle_cpu = -1.0;
  // Until every result is in, every side job given out is back and none is still to appear (made
  // from delivered results elsewhere); meanwhile rank 0 takes side jobs itself when it has
  // nothing else to do.
  while (received_ < total || jobs_out_ > 0 || (opts_.side_jobs_pending && opts_.side_jobs_pending())) {
    const bool progressed = poll();
    if (received_ == total && handle_cpu < 0) handle_cpu = thread_cpu_s() - cpu0 - compute_cpu_s_ - local_jobs_cpu_;
    if (next_run_ < todo_.size()) {
      compute_one();
    } else if (!progressed && !local_job()) {
      const auto ti = Clock::now();
      backoff.sleep();
      sum_.rank0_idle_s += seconds_since(ti);
    } else {
      backoff.reset();
    }
    maybe_tick();
  }
  // Workers still waiting for a batch get the stop message.
  final_ = true;
  {
    ScopeTimer t(sum_.rank0_poll_s);
    for (int w = 1; w < size_; ++w)
      if (!stopped_[static_cast<std::size_t>(w)]) send_batch(w);
  }
  for (std::size_t i = 0; i < sends_.size(); ++i) {
    wait_idle(&send_reqs_[i]);
    job_sent(*sends_[i]);
  }
  sends_.clear();
  send_reqs_.clear();
  sum_.wall_s = seconds_since(t0);
  on_tick_();
  sum_.rank0_handle_cpu_s = handle_cpu >= 0 ? handle_cpu : thread_cpu_s() - cpu0 - compute_cpu_s_ - local_jobs_cpu_;
  sum_.rank0_compute_cpu_s = compute_cpu_s_;
  return sum_;
}

}  // namespace

std::string ScheduleOptions::validate() const {
  if (max_batch < 1) return fmt::format("max_batch: must be >= 1, got {}", max_batch);
  if (batches_per_rank < 1) return fmt::format("batches_per_rank: must be >= 1, got {}", batches_per_rank);
  if (!(tick_interval_s > 0.0)) return fmt::format("tick_interval_s: must be positive, got {}", tick_interval_s);
  if (take_job && !on_job_done) return "take_job needs on_job_done";
  return {};
}

ScheduleSummary run_schedule(MPI_Comm comm, const std::vector<std::int64_t>& todo, const ComputeFn& compute,
                             const ResultFn& on_result, const TickFn& on_tick, const ScheduleOptions& opts) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("schedule options: " + e);  // same on every rank
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank != 0) {
    run_worker(comm, compute, opts);
    return {};
  }
  return Rank0(comm, todo, compute, on_result, on_tick, opts).run();
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
