// The round loop on every rank, rank 0's side of a round's schedule and of the chunks (the
// worker's schedule is in worker.cpp, a rank's messaging in node.cpp).
#include "parallel/engine.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdint>
#include <ctime>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "parallel/engine_detail.hpp"
#include "parallel/interrupt.hpp"
#include "parallel/owner.hpp"
#include "results/chunk_stats.hpp"
#include "util/bytes.hpp"

namespace truss::parallel {

double detail::thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

using namespace detail;

namespace {

constexpr auto kPollInterval = std::chrono::milliseconds(50);  // bounds how late a chunk is placed
// Rank 0 idle (the end of a round, the last chunks) looks at its messages once a millisecond: a
// look that finds nothing costs it about as much CPU as tens of costless results (the MPI library
// yields the core when oversubscribed, and each sleep is a context switch), and rank 0's answers
// at the end wait for nothing faster than that.
constexpr long kRank0IdleUs = 1000;

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

// Rank 0's fatal error: the results file's temporary name removed (the journal keeps every finished
// run for --resume), then the job aborted.
[[noreturn]] void abort_rank0(MPI_Comm comm, Collector& collector, const char* where, const std::exception& e) {
  collector.remove_temporary_file();
  abort_job(comm, where, e);
}

class Rank0Round;

// Rank 0's answers to the owners' messages (per round part and per chunk), and the batches done
// handed to the round being scheduled.
class Rank0Server {
 public:
  Rank0Server(Node& node, Collector& collector, results::ScheduleSummary& sum, const campaign::RecordLayout& layout,
              int stats_ranks)
      : node_(node), collector_(collector), sum_(sum), layout_(layout), stats_ranks_(stats_ranks) {}
  void handle(int tag, int source, std::string& bytes);
  Rank0Round* round = nullptr;
  int finished = 0;  // owners that have written and synced every chunk they own

 private:
  Node& node_;
  Collector& collector_;
  results::ScheduleSummary& sum_;
  results::ChunkReport report_;
  const campaign::RecordLayout& layout_;
  int stats_ranks_;
  std::vector<results::StatsPart> stats_parts_;  // until every statistics rank's is in
};

// Rank 0 in one round: hands out the round's runs in index order in guided batches, computes one
// run at a time itself, and between its runs serves the messages (answering a batch done at once
// with the next batch) and its own chunks, until every record of the round is in and every batch
// handed out has said it is done: a worker sends its batch's records before its done message, so
// the last records can complete the round while that message is still on its way, and it belongs
// to this round.
class Rank0Round {
 public:
  Rank0Round(Node& node, const methods::RoundPlan& plan, Collector& collector, const Evaluate& evaluate,
             const std::function<bool()>& serve, const EngineOptions& opts, results::ScheduleSummary& sum);
  void run();
  void on_done(int worker) {
    --batches_out_;
    send_batch(worker);
  }

 private:
  std::int64_t batch_size() const;
  void send_batch(int w);
  std::int64_t take(std::int64_t k, std::string& ranges);  // the round's next k runs not in the journals
  void announce_drained();
  bool poll_due(Clock::time_point last_poll) const;
  void compute_stretch(Clock::time_point last_poll);
  void compute_one();
  void maybe_tick();

  Node& node_;
  const methods::RoundPlan& plan_;
  Collector& collector_;
  const Evaluate& evaluate_;
  const std::function<bool()>& serve_;
  const EngineOptions& opts_;
  results::ScheduleSummary& sum_;
  std::int64_t cursor_, to_do_ = 0, handed_ = 0, runs_since_poll_ = 0, batches_out_ = 0;
  std::vector<std::uint8_t> waiting_;
  std::string one_, ranges_;
  Clock::time_point last_tick_ = Clock::now();
};

void Rank0Server::handle(int tag, int source, std::string& bytes) {
  ScopeTimer t(sum_.rank0_result_s);
  if (tag == kTagDone) {
    if (!round) throw std::runtime_error(fmt::format("a batch done by rank {} outside a round", source));
    util::ByteReader in(bytes, "a batch's status counts");
    const auto counts = in.get<results::StatusCounts>();
    in.expect_end();
    for (std::size_t st = 0; st < counts.size(); ++st)
      collector_.add_computed(static_cast<std::int8_t>(st), counts[st]);
    round->on_done(source);
  } else if (tag == kTagPart) {
    collector_.add_part(results::read_round_part(bytes, collector_.n_observed()));
  } else if (tag == kTagChunk) {
    results::read_chunk_report(bytes, report_);
    node_.send(source, kTagPlacement, results::to_bytes(collector_.place(report_)));
  } else if (tag == kTagStats) {
    stats_parts_.push_back(results::read_stats_part(bytes));
    sum_.stats_merge_cpu_s = std::max(sum_.stats_merge_cpu_s, stats_parts_.back().merge_cpu_s);
    if (static_cast<int>(stats_parts_.size()) == stats_ranks_)
      collector_.set_stats(results::assemble_streamed_stats(layout_, std::move(stats_parts_)));
  } else if (tag == kTagFinished) {
    ++finished;
  } else {
    throw std::runtime_error(fmt::format("rank 0 got a message of tag {} from rank {}", tag, source));
  }
}

Rank0Round::Rank0Round(Node& node, const methods::RoundPlan& plan, Collector& collector, const Evaluate& evaluate,
                       const std::function<bool()>& serve, const EngineOptions& opts, results::ScheduleSummary& sum)
    : node_(node), plan_(plan), collector_(collector), evaluate_(evaluate), serve_(serve), opts_(opts), sum_(sum),
      cursor_(plan.first_run) {
  waiting_.assign(static_cast<std::size_t>(node.size()), 0);
  for (std::int64_t i = plan.first_run; i < plan.end_run(); ++i) to_do_ += !collector.has(i);  // --resume: some are in
}

// Guided batches (EngineOptions): remaining / (batches_per_rank * ranks), at least kMinBatchS of
// runs (at rank 0's wall time per run so far, every round's; 1 before it has computed one), at
// most max_batch and a chunk.
std::int64_t Rank0Round::batch_size() const {
  const std::int64_t cap = std::min<std::int64_t>(opts_.max_batch, node_.chunk_runs());
  const double runs = static_cast<double>(sum_.runs_by_rank0), wall_s = sum_.rank0_compute_s;
  const std::int64_t least =
      wall_s > 0.0 ? static_cast<std::int64_t>(std::min(kMinBatchS * runs / wall_s, static_cast<double>(cap))) : 1;
  const std::int64_t guided = (to_do_ - handed_) / (std::int64_t{opts_.batches_per_rank} * node_.size());
  return std::clamp<std::int64_t>(guided, std::max<std::int64_t>(least, 1), cap);
}

// Appends the ranges; returns the first run of the last one (the run, for k = 1).
std::int64_t Rank0Round::take(std::int64_t k, std::string& ranges) {
  handed_ += k;
  if (handed_ == to_do_) announce_drained();
  std::int64_t first = 0;
  while (k > 0) {
    while (collector_.has(cursor_)) ++cursor_;
    first = cursor_;
    while (k > 0 && !collector_.has(cursor_)) {
      ++cursor_;
      --k;
    }
    util::put(ranges, first);
    util::put(ranges, cursor_ - first);
  }
  return first;
}

// The round's last runs are handed out: each worker that may still hold some is told, so that it
// runs them before its chunks' work (which may wait, while the round waits for its last run).
void Rank0Round::announce_drained() {
  std::string round;
  util::put(round, plan_.round);
  for (int w = 1; w < node_.size(); ++w)
    if (!waiting_[static_cast<std::size_t>(w)]) node_.send(w, kTagDrained, std::string(round));
}

// A worker that asks when no run is left waits for the end of the round.
void Rank0Round::send_batch(int w) {
  const std::int64_t k = std::min(batch_size(), to_do_ - handed_);
  if (k == 0) {
    waiting_[static_cast<std::size_t>(w)] = 1;
    return;
  }
  std::string out;
  take(k, out);
  ++batches_out_;
  node_.send(w, kTagWork, std::move(out));
}

// Rank 0 takes runs from the same pool one at a time, so it is never more than one run late in
// answering a worker; its records go to their owners as a worker's do (Node::route).
void Rank0Round::compute_one() {
  ranges_.clear();
  const std::int64_t run = take(1, ranges_);
  one_.clear();
  try {
    evaluate_(plan_, run, one_);
    node_.route(one_, run);
    collector_.add_computed(static_cast<std::int8_t>(one_[node_.status_at()]));
  } catch (const std::exception& e) {
    abort_rank0(node_.comm(), collector_, "a run", e);
  }
  ++sum_.runs_by_rank0;
  if (handed_ == to_do_) node_.flush_records();
}

// Between its runs rank 0 looks at its messages after half a batch of them or kPollInterval,
// whichever comes first: a worker holds a second batch of runs, so it does not notice (each look
// costs about what a costless run's result used to cost in all, a yield of the core when
// oversubscribed).
bool Rank0Round::poll_due(Clock::time_point last_poll) const {
  return runs_since_poll_ >= std::max<std::int64_t>(1, batch_size() / 2) || Clock::now() - last_poll >= kPollInterval;
}

// Runs back to back until a look at the messages is due: the thread's CPU clock (a system call,
// about as dear as the look) is read once per stretch, not per run.
void Rank0Round::compute_stretch(Clock::time_point last_poll) {
  const auto t0 = Clock::now();
  const double c0 = thread_cpu_s();
  do {
    compute_one();
    node_.progress_records();
    ++runs_since_poll_;
  } while (handed_ < to_do_ && !node_.flow_blocked() && !poll_due(last_poll) && !interrupted());
  sum_.rank0_compute_cpu_s += thread_cpu_s() - c0;
  sum_.rank0_compute_s += seconds_since(t0);
}

void Rank0Round::maybe_tick() {
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_tick_).count() < opts_.tick_interval_s) return;
  last_tick_ = now;
  try {
    collector_.tick(false);
  } catch (const std::exception& e) {
    abort_rank0(node_.comm(), collector_, "syncing the journal", e);
  }
  sum_.rank0_tick_s += seconds_since(now);
}

// Until every record of the round is in: serve the messages, then rank 0's chunks, else compute
// a run, else wait a little; then until every batch done is in. Then every worker gets the end of
// the round.
void Rank0Round::run() {
  for (int w = 1; w < node_.size(); ++w) send_batch(w);
  for (int w = 1; w < node_.size(); ++w)
    if (!waiting_[static_cast<std::size_t>(w)]) send_batch(w);
  Backoff backoff(kRank0IdleUs, kRank0IdleUs);  // only at the end of a round: a millisecond late at most
  Clock::time_point last_poll{};
  while (!collector_.round_complete(plan_) || batches_out_ > 0) {
    bool progressed = false;
    if (handed_ == to_do_ || node_.flow_blocked() || poll_due(last_poll)) {
      last_poll = Clock::now();
      runs_since_poll_ = 0;
      progressed = node_.poll();
    }
    const bool served = serve_();
    if (!served && handed_ < to_do_ && !node_.flow_blocked()) {
      compute_stretch(last_poll);
    } else if (!served && !progressed) {
      ScopeTimer t(sum_.rank0_idle_s);
      if (node_.has_unsent_records()) node_.flush_records();
      backoff.sleep();
    } else {
      backoff.reset();
    }
    maybe_tick();
  }
  for (int w = 1; w < node_.size(); ++w) node_.send(w, kTagWork, {});  // the end of the round: no runs
}

// Round r's plan from rank 0 to every rank, serving the rank's messages and chunks while it travels:
// its round, first run, run count and state length, then its state, sent from and received into
// `plan` (rank 0 sends its own, the others receive it).
void broadcast_plan(Node& node, methods::RoundPlan& plan, const std::function<bool()>& serve) {
  const bool root = node.rank() == 0;
  std::int64_t head[4] = {plan.round, plan.first_run, plan.n_runs, static_cast<std::int64_t>(plan.state.size())};
  if (root && head[3] > std::numeric_limits<int>::max())  // one broadcast's count is an int
    throw std::runtime_error(fmt::format("round {}: a plan of {} bytes (at most {})", plan.round, head[3],
                                         std::numeric_limits<int>::max()));
  MPI_Request r;
  MPI_Ibcast(head, 4, MPI_INT64_T, 0, node.comm(), &r);
  wait_serving(&r, node, serve);
  if (!root) {
    if (head[2] < 0 || head[3] < 0 || head[3] > std::numeric_limits<int>::max())
      throw std::runtime_error(fmt::format("round {}: a plan of {} runs and {} bytes", head[0], head[2], head[3]));
    plan = {head[0], head[1], head[2], std::string(static_cast<std::size_t>(head[3]), '\0')};
  }
  MPI_Ibcast(plan.state.data(), static_cast<int>(head[3]), MPI_BYTE, 0, node.comm(), &r);
  wait_serving(&r, node, serve);
}

}  // namespace

std::string EngineOptions::validate() const {
  if (max_batch < 1) return fmt::format("max_batch: must be >= 1, got {}", max_batch);
  if (batches_per_rank < 1) return fmt::format("batches_per_rank: must be >= 1, got {}", batches_per_rank);
  if (!(tick_interval_s > 0.0)) return fmt::format("tick_interval_s: must be positive, got {}", tick_interval_s);
  if (!(flush_interval_s > 0.0)) return fmt::format("flush_interval_s: must be positive, got {}", flush_interval_s);
  if (statistics_ranks < 0) return fmt::format("statistics_ranks: must be >= 0, got {}", statistics_ranks);
  return {};
}

results::StatsRanks find_stats_ranks(int asked, int size, bool restores, std::size_t n_stats) {
  if (size <= 1 || restores) return {0, 1};
  const int wanted = asked > 0 ? asked : (size - 1 + kRanksPerStatisticsRank - 1) / kRanksPerStatisticsRank;
  const auto columns = static_cast<int>(std::min<std::size_t>(std::max<std::size_t>(n_stats, 1), 1 << 30));
  return {1, std::min({wanted, size - 1, columns})};
}

struct Engine::Impl {
  Impl(MPI_Comm comm, std::int64_t chunk_runs, std::size_t status_offset, const EngineOptions& o)
      : node(comm, chunk_runs, status_offset), opts(o) {}
  void handle(int tag, int source, std::string& bytes);
  bool serve(double budget_s = kServeSliceS);  // the rank's chunks: steps until budget_s has passed
  // The statistics rank, every round ended (its owner knows the campaign's chunks): the statistics
  // to rank 0 once all are merged; true when it sends them.
  bool send_stats() { return stats && owner->ended() && stats->send_if_complete(owner->n_chunks()); }
  void drain(bool root);
  Node node;
  EngineOptions opts;
  ChunkOwner* owner = nullptr;
  Collector* collector = nullptr;
  std::unique_ptr<Rank0Server> server;
  std::unique_ptr<StatsServer> stats;  // on a statistics rank
  int stats_ranks = 1;
  WorkQueue work;
  results::ScheduleSummary schedule;
};

void Engine::Impl::handle(int tag, int source, std::string& bytes) {
  if (tag == kTagWork) work.push(std::move(bytes));
  else if (tag == kTagDrained) {
    util::ByteReader in(bytes, "a drained round's notice");
    work.set_drained(in.get<std::int64_t>());
    in.expect_end();
  }
  else if (tag == kTagRecords) owner->add_records(bytes);
  else if (tag == kTagPlacement) owner->on_placement(bytes);
  else if (tag == kTagWindows) owner->on_windows(source, bytes);
  else if (tag == kTagAskSeed) owner->on_seed_ask(source);
  else if (stats && StatsServer::handles(tag)) {
    ScopeTimer t(schedule.rank0_result_s);  // (rank 0's figure, when it is the statistics rank)
    stats->handle(tag, source, bytes);
  } else if (server) server->handle(tag, source, bytes);
  else throw std::runtime_error(fmt::format("rank {} got a message of tag {} from rank {}", node.rank(), tag, source));
}

bool Engine::Impl::serve(double budget_s) {
  const auto t0 = Clock::now();
  bool any = false;
  while (owner->step()) {
    any = true;
    if (seconds_since(t0) > budget_s) break;
  }
  node.pause_records(owner->behind());
  if (any) schedule.rank0_write_s += seconds_since(t0);  // rank 0's: its own chunks' work
  return any;
}

// After the last round: every chunk built, placed and written; each owner says so once its bytes
// are synced, and rank 0 waits for all of them.
void Engine::Impl::drain(bool root) {
  Backoff backoff = root ? Backoff(kRank0IdleUs, kRank0IdleUs) : Backoff();
  bool finished = false;
  while (!finished || (stats && !stats->sent()) ||
         (root && (server->finished < node.size() || !collector->stats()))) {
    const bool worked = node.poll() | serve() | send_stats();
    if (!finished && owner->done()) {
      owner->finish();
      node.send(0, kTagFinished, {});
      finished = true;
    }
    if (worked) backoff.reset();
    else backoff.sleep();
    if (root) collector->tick(false);
  }
}

Engine::Engine(MPI_Comm comm, std::int64_t chunk_runs, std::size_t status_offset, const EngineOptions& opts)
    : impl_(std::make_unique<Impl>(comm, chunk_runs, status_offset, opts)) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("engine options: " + e);
}

Engine::~Engine() = default;

std::function<void(int, int, std::string)> Engine::sender() {
  Node* node = &impl_->node;
  return [node](int dest, int tag, std::string bytes) { node->send(dest, tag, std::move(bytes)); };
}

void Engine::attach(ChunkOwner& owner, Collector* collector, results::StatsRanks stats) {
  Impl& m = *impl_;
  if ((m.node.rank() == 0) != (collector != nullptr)) throw std::invalid_argument("engine: the collector is rank 0's");
  const std::size_t n_stats = owner.n_statistics_columns();
  if (stats.first < 0 || stats.count < 1 || stats.first + stats.count > m.node.size() ||
      static_cast<std::size_t>(stats.count) > std::max<std::size_t>(n_stats, 1))
    throw std::invalid_argument(fmt::format("engine: statistics ranks {} to {} of {} ranks ({} columns)", stats.first,
                                            stats.first + stats.count - 1, m.node.size(), n_stats));
  m.owner = &owner;
  m.collector = collector;
  m.stats_ranks = stats.count;
  if (collector)
    m.server = std::make_unique<Rank0Server>(m.node, *collector, m.schedule, owner.layout(), stats.count);
  if (stats.holds(m.node.rank()))
    m.stats = std::make_unique<StatsServer>(m.node, owner.layout(), stats.find_columns(m.node.rank(), n_stats));
  m.node.set_handler([&m](int tag, int source, std::string& bytes) { m.handle(tag, source, bytes); });
}

void Engine::serve_local() {
  Impl& m = *impl_;
  while (m.node.poll_local() | m.serve() | m.send_stats()) {
  }
}

void Engine::set_rank0_chunks(std::vector<std::int64_t> chunks) { impl_->node.set_rank0_chunks(std::move(chunks)); }

EngineResult Engine::run(const Evaluate& evaluate) {
  Impl& m = *impl_;
  Node& node = m.node;
  const bool root = node.rank() == 0;
  m.schedule = {};
  m.schedule.statistics_ranks = m.stats_ranks;
  EngineResult out;
  const std::function<bool()> serve = [&m] { return m.serve(); };
  const std::function<bool(double)> serve_for = [&m](double budget_s) { return m.serve(budget_s); };
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_s();
  std::int64_t first = 0;
  const std::int64_t restored = root ? m.collector->n_done() : 0;
  double sched_wall = 0.0;
  try {
    for (std::int64_t r = 0;; ++r) {
      methods::RoundPlan plan = root ? m.collector->plan_round(r, first) : methods::RoundPlan{};
      broadcast_plan(node, plan, serve);
      if (plan.n_runs == 0) break;
      ++out.n_rounds;
      m.owner->add_round(plan);
      if (root) {
        Rank0Round round(node, plan, *m.collector, evaluate, serve, m.opts, m.schedule);
        m.server->round = &round;
        round.run();
        m.server->round = nullptr;
      } else {
        run_worker_round(node, m.work, plan, evaluate, serve_for);
      }
      first = plan.end_run();
    }
    sched_wall = seconds_since(t0);
    const auto t_drain = Clock::now();
    m.owner->end_rounds();
    m.drain(root);
    out.last_chunks_s = seconds_since(t_drain);
  } catch (const Interrupted&) {
    throw;
  } catch (const std::exception& e) {
    if (root) abort_rank0(node.comm(), *m.collector, "the campaign's engine", e);
    abort_job(node.comm(), "the campaign's engine", e);
  }
  if (root) {
    out.schedule = m.schedule;
    out.schedule.schedule_wall_s = sched_wall;
    out.schedule.rank0_poll_s = node.poll_s();
    out.schedule.rank0_mpi_s = node.mpi_s();
    out.schedule.rank0_handle_cpu_s = thread_cpu_s() - cpu0 - m.schedule.rank0_compute_cpu_s;
    out.schedule.runs_by_workers = m.collector->n_done() - restored - out.schedule.runs_by_rank0;
  }
  return out;
}

}  // namespace truss::parallel
