// Internals shared by the two sides of the scheduler (scheduler.cpp: rank 0; scheduler_worker.cpp).
#pragma once
#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>

#include "parallel/scheduler.hpp"

namespace truss::parallel::detail {

// rank 0 -> worker: the job, n int64 run indices, then u32 n and u32 job bytes (a trailer, so that
// rank 0 sends a side job from its own buffer without copying it); n = 0 and no job: no more work
inline constexpr int kTagWork = 11;
inline constexpr std::size_t kWorkTrailer = 2 * sizeof(std::uint32_t);
inline constexpr int kTagResult = 12;  // worker -> rank 0: u32 job output bytes, the output, framed results of one batch (and a request)

// Results of a batch: for each run, u32 length then the bytes.
inline void append_framed(std::string& msg, const std::string& one) {
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

[[noreturn]] void abort_job(MPI_Comm comm, const char* where, const std::exception& e);

// Sleeps between polls: 20 us at first, doubling up to max_us; reset() after progress.
class Backoff {
 public:
  explicit Backoff(long max_us = 1000) : max_us_(max_us) {}
  void sleep();
  void reset() { us_ = 20; }

 private:
  long us_ = 20, max_us_;
};

void run_worker(MPI_Comm comm, const ComputeFn& compute, const ScheduleOptions& opts);

}  // namespace truss::parallel::detail
