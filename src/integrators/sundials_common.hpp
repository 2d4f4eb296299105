// What the CVODE and IDA integrators share: the SUNDIALS context of an integrator, the event
// callbacks' handling of an exception, and the dense output over the solver's last step. The
// return-flag checks are in sundials_checks.hpp, the callbacks' deadline in callback_deadline.hpp.
#pragma once
#include <algorithm>
#include <exception>
#include <limits>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "integrators/ode.hpp"
#include "integrators/sundials_checks.hpp"

namespace truss::integrators::sundials {

// The SUNContext of one integrator: created with its first problem, kept across problems, freed
// last (declare it before the objects made in it).
class Context {
 public:
  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context() {
    if (ctx_) SUNContext_Free(&ctx_);
  }
  // False (and sum says why) when it cannot be created.
  bool ensure(const char* solver, IntegratorSummary& sum) {
    return ctx_ || sunflags::check_sundials(SUNContext_Create(nullptr, &ctx_), solver, "SUNContext_Create", sum);
  }
  SUNContext get() const { return ctx_; }

 private:
  SUNContext ctx_ = nullptr;
};

// The event functions of sys at (t, y) into g, inside a SUNDIALS root callback: an exception is
// kept in `error` for the integrator to rethrow once the solver has returned, and -1 stops the
// solver (C code cannot unwind).
inline int call_events(OdeSystem& sys, std::exception_ptr& error, double t, const double* y, double* g) {
  try {
    sys.calc_events(t, y, g);
  } catch (...) {
    error = std::current_exception();
    return -1;
  }
  return 0;
}

// The solver's interpolant over its last step: get_dky (CVodeGetDky, IDAGetDky) of order 0 into
// tmp, then copy(tmp, y) of the system's state. Where get_dky fails, y is NaN and the first failed
// flag of the step is kept in `flag` for the integrator to check after the observer.
template <class GetDky, class Copy>
class Dense : public DenseOutput {
 public:
  Dense(GetDky get_dky, void* mem, N_Vector tmp, int n, Copy copy)
      : get_dky_(get_dky), mem_(mem), tmp_(tmp), n_(n), copy_(copy) {}
  mutable int flag = 0;
  void calc_state(double t, double* y) const override {
    const int f = get_dky_(mem_, t, 0, tmp_);
    if (f < 0) {
      std::fill_n(y, n_, std::numeric_limits<double>::quiet_NaN());
      if (flag >= 0) flag = f;
      return;
    }
    copy_(tmp_, y);
  }

 private:
  GetDky get_dky_;
  void* mem_;
  N_Vector tmp_;
  int n_;
  Copy copy_;
};

}  // namespace truss::integrators::sundials
