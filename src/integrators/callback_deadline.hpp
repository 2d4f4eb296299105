// The wall-time cap as the SUNDIALS callbacks read it (StepObserver::deadline): a callback that
// finds it passed returns an unrecoverable flag, the solver returns, and the integrator reports
// IntegratorStatus::deadline. Shared by the CVODE and IDA integrators.
#pragma once
#include <chrono>

namespace truss::integrators {

struct CallbackDeadline {
  using Clock = std::chrono::steady_clock;
  Clock::time_point deadline = Clock::time_point::max();
  bool hit = false;  // a callback found the deadline passed

  // A new integrate() call.
  void reset(Clock::time_point d) {
    deadline = d;
    hit = false;
    count_ = 0;
  }
  // Read by the right-hand side / residual: the clock every kEvery calls (a call of a long stack
  // costs tens of microseconds, a clock read tens of nanoseconds).
  bool passed_every() {
    if (deadline == Clock::time_point::max() || ++count_ % kEvery != 0) return hit;
    return passed_now();
  }
  // The clock now (the LU, once per column).
  bool passed_now() {
    if (deadline != Clock::time_point::max() && Clock::now() > deadline) hit = true;
    return hit;
  }

 private:
  static constexpr long kEvery = 8;
  long count_ = 0;
};

}  // namespace truss::integrators
