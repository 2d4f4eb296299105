#include "parallel/scheduler.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <ctime>
#include <exception>

#include <fmt/format.h>

namespace truss::parallel {

namespace {

constexpr int kTagWork = 11;    // rank 0 -> worker: int64 run indices; empty = no more work
constexpr int kTagResult = 12;  // worker -> rank 0: framed results of one batch (and a request)

using Clock = std::chrono::steady_clock;

// Results of a batch: for each run, u32 length then the bytes.
void append_framed(std::string& msg, const std::string& one) {
  const auto n = static_cast<std::uint32_t>(one.size());
  msg.append(reinterpret_cast<const char*>(&n), sizeof n);
  msg += one;
}

template <class F>
void for_each_framed(std::string_view msg, F&& f) {
  std::size_t at = 0;
  while (at < msg.size()) {
    std::uint32_t n = 0;
    std::memcpy(&n, msg.data() + at, sizeof n);
    at += sizeof n;
    f(msg.substr(at, n));
    at += n;
  }
}

[[noreturn]] void abort_job(MPI_Comm comm, const char* where, const std::exception& e) {
  std::fprintf(stderr, "truss-campaign: fatal error in %s: %s\n", where, e.what());
  std::fflush(stderr);
  MPI_Abort(comm, 3);
  std::terminate();
}

void run_worker(MPI_Comm comm, const ComputeFn& compute) {
  std::vector<std::int64_t> cur, next;
  auto recv_work = [&](std::vector<std::int64_t>& into) {
    MPI_Status st;
    MPI_Probe(0, kTagWork, comm, &st);
    int count = 0;
    MPI_Get_count(&st, MPI_INT64_T, &count);
    into.resize(static_cast<std::size_t>(count));
    MPI_Recv(into.data(), count, MPI_INT64_T, 0, kTagWork, comm, MPI_STATUS_IGNORE);
  };
  // Rank 0 sends two batches up front; afterwards one per result message, so the second batch
  // (or the stop message) is already on its way while this one is computed.
  recv_work(cur);
  std::string msg, one;
  MPI_Request send_req = MPI_REQUEST_NULL;
  std::string sending;
  while (!cur.empty()) {
    msg.clear();
    for (std::int64_t run : cur) {
      one.clear();
      try {
        compute(run, one);
      } catch (const std::exception& e) {
        abort_job(comm, "a run", e);
      }
      append_framed(msg, one);
    }
    MPI_Wait(&send_req, MPI_STATUS_IGNORE);
    sending.swap(msg);
    MPI_Isend(sending.data(), static_cast<int>(sending.size()), MPI_BYTE, 0, kTagResult, comm, &send_req);
    recv_work(next);
    cur.swap(next);
  }
  MPI_Wait(&send_req, MPI_STATUS_IGNORE);
}

}  // namespace

std::string ScheduleOptions::validate() const {
  if (max_batch < 1) return fmt::format("max_batch: must be >= 1, got {}", max_batch);
  if (batches_per_rank < 1) return fmt::format("batches_per_rank: must be >= 1, got {}", batches_per_rank);
  if (!(tick_interval_s > 0.0)) return fmt::format("tick_interval_s: must be positive, got {}", tick_interval_s);
  return {};
}

ScheduleSummary run_schedule(MPI_Comm comm, const std::vector<std::int64_t>& todo, const ComputeFn& compute,
                             const ResultFn& on_result, const TickFn& on_tick, const ScheduleOptions& opts) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  ScheduleSummary sum;
  if (rank != 0) {
    run_worker(comm, compute);
    return sum;
  }
  std::size_t next_run = 0;                // todo[next_run] is the next run to hand out
  std::int64_t received = 0;
  const auto total = static_cast<std::int64_t>(todo.size());
  std::vector<std::uint8_t> stopped(static_cast<std::size_t>(size), 0);

  auto take_batch = [&](std::vector<std::int64_t>& batch) {
    batch.clear();
    const std::size_t remaining = todo.size() - next_run;
    std::size_t k = remaining / static_cast<std::size_t>(opts.batches_per_rank * size);
    k = std::clamp<std::size_t>(k, 1, static_cast<std::size_t>(opts.max_batch));
    k = std::min(k, remaining);
    batch.assign(todo.begin() + static_cast<std::ptrdiff_t>(next_run), todo.begin() + static_cast<std::ptrdiff_t>(next_run + k));
    next_run += k;
  };
  std::vector<std::int64_t> batch;
  auto send_batch = [&](int w) {
    take_batch(batch);
    if (batch.empty()) stopped[static_cast<std::size_t>(w)] = 1;
    MPI_Send(batch.data(), static_cast<int>(batch.size()), MPI_INT64_T, w, kTagWork, comm);
    ++sum.batches_sent;
  };
  for (int w = 1; w < size; ++w) send_batch(w);
  for (int w = 1; w < size; ++w)
    if (!stopped[static_cast<std::size_t>(w)]) send_batch(w);

  auto deliver = [&](std::string_view one) {
    try {
      on_result(one);
    } catch (const std::exception& e) {
      abort_job(comm, "storing a result", e);
    }
    ++received;
  };
  std::string msg;
  auto serve_one = [&](const MPI_Status& st) {
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    msg.resize(static_cast<std::size_t>(count));
    MPI_Recv(msg.data(), count, MPI_BYTE, st.MPI_SOURCE, kTagResult, comm, MPI_STATUS_IGNORE);
    sum.bytes_received += count;
    for_each_framed(msg, deliver);
    if (!stopped[static_cast<std::size_t>(st.MPI_SOURCE)]) send_batch(st.MPI_SOURCE);
  };
  auto last_tick = Clock::now();
  auto maybe_tick = [&] {
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - last_tick).count() >= opts.tick_interval_s) {
      last_tick = now;
      on_tick();
    }
  };

  std::string one;
  while (received < total) {
    // Answer every waiting worker first: they must never wait for rank 0's own run.
    for (;;) {
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, comm, &flag, &st);
      if (!flag) break;
      serve_one(st);
    }
    // Rank 0 takes single runs from the same pool, so it is never more than one run late in
    // answering a worker.
    if (next_run < todo.size()) {
      const std::int64_t run = todo[next_run++];
      one.clear();
      try {
        compute(run, one);
      } catch (const std::exception& e) {
        abort_job(comm, "a run", e);
      }
      ++sum.runs_by_rank0;
      deliver(one);
    } else if (received < total) {
      MPI_Status st;
      // Nothing left to compute here: wait for results, waking up for the ticks.
      int flag = 0;
      while (!flag) {
        MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, comm, &flag, &st);
        if (!flag) {
          maybe_tick();
          struct timespec ts{0, 200000};  // 0.2 ms: rank 0 idles only at the very end
          nanosleep(&ts, nullptr);
        }
      }
      serve_one(st);
    }
    maybe_tick();
  }
  // Workers still waiting for a batch get the stop message.
  for (int w = 1; w < size; ++w)
    if (!stopped[static_cast<std::size_t>(w)]) send_batch(w);
  on_tick();
  return sum;
}

}  // namespace truss::parallel
