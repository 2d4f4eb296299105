// Internals shared by the two sides of a round's schedule (engine.cpp: rank 0; worker.cpp).
#pragma once
#include <mpi.h>

#include <exception>

#include "parallel/engine.hpp"

namespace truss::parallel::detail {

inline constexpr int kTagWork = 11;    // rank 0 -> worker: i64 run indices; none: the round is over
inline constexpr int kTagResult = 12;  // worker -> rank 0: the batch's records, sealed journal frames

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

// A worker's part of round `plan`: batches in, their records out, until the round is over.
void run_worker_round(MPI_Comm comm, const methods::RoundPlan& plan, const Evaluate& evaluate);

}  // namespace truss::parallel::detail
