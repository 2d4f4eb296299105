// One driver for the SUNDIALS integrators (CVODE, cvode_integrator.hpp; IDA, ida_integrator.hpp),
// as EmbeddedRungeKutta is for the explicit pairs: SundialsIntegrator holds a solver (a
// SundialsSolver: the SUNDIALS objects of CVODE or IDA, their set-up and restart, their callbacks)
// and runs the one step loop: one step per call (CV_ONE_STEP, IDA_ONE_STEP), the call's step budget,
// the counters, the solver's interpolant (CVodeGetDky, IDAGetDky) as the observer's dense output,
// the events from the solver's root finding, the wall-time cap read inside the callbacks, an
// exception of a callback rethrown once the solver has returned, and every return flag checked: a
// failure ends the call with IntegratorStatus::failure naming the solver, the function and the flag.
// After a failure the solver's objects are freed and made afresh by the next call.
#pragma once
#include <chrono>
#include <exception>
#include <memory>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "integrators/callback_deadline.hpp"
#include "integrators/ode.hpp"
#include "integrators/sundials_checks.hpp"

namespace truss::integrators {

// A solver's functions and names that the step loop calls; the functions of CVODE and IDA that it
// uses have the same signatures.
struct SundialsApi {
  const char* solver;      // "CVODE", in messages
  const char* a_step;      // "a CVODE step"
  const char* evaluation;  // "right-hand side": what its callback evaluates
  char* (*flag_name)(long int);
  int success, root_return, tstop_return, too_much_work;
  int (*get_num_steps)(void*, long int*);
  int (*get_num_err_test_fails)(void*, long int*);
  int (*get_root_info)(void*, int*);
  int (*get_dky)(void*, double, int, N_Vector);
  // The names of the four functions above, in that order.
  const char* names[4];
};

// What a solver's callbacks (right-hand side or residual, roots, Jacobian, linear solver) report
// to the step loop through their user data; reset by every start.
struct CallbackState {
  long evals = 0;             // right-hand side or residual evaluations
  long nonfinite = 0;         // of which returned NaN or inf (the solver retried smaller steps)
  std::exception_ptr error;   // thrown inside a callback, rethrown after the solver returned
  CallbackDeadline clock;     // the wall-time cap
  void reset(std::chrono::steady_clock::time_point deadline) {
    reset_counts();
    clock.reset(deadline);
  }
  void reset_counts() {
    evals = nonfinite = 0;
    error = nullptr;
  }
};

// A SUNDIALS solver as the step loop drives it (the traits object of SundialsIntegrator): its
// objects, created on first use and kept across calls, and what differs between CVODE and IDA.
class SundialsSolver {
 public:
  explicit SundialsSolver(const SundialsApi& api) : api_(api) {}
  virtual ~SundialsSolver() = default;
  SundialsSolver(const SundialsSolver&) = delete;  // owns SUNDIALS memory
  SundialsSolver& operator=(const SundialsSolver&) = delete;
  const SundialsApi& api() const { return api_; }
  // (Re)starts the solver on sys from (t0, y0) towards t_end with the options of this call: false,
  // with sum's status and message, when it cannot (a flag, the system unsuitable, the deadline).
  virtual bool start(OdeSystem& sys, double t0, double t_end, const double* y0, const IntegratorOptions& o,
                     IntegratorSummary& sum) = 0;
  // One step (ONE_STEP mode) towards t_end: the solver's flag, the time reached in t.
  virtual int step(double t_end, double& t) = 0;
  // The system's state from one of the solver's vectors (its state or its interpolant's output).
  virtual void copy_state(N_Vector v, double* y) const = 0;
  // Everything but the context: the next start makes the objects afresh.
  virtual void free_problem() = 0;
  // Set by start(): the solver's memory, its state vector, a scratch vector for the interpolant,
  // the size of the system's state.
  void* mem = nullptr;
  N_Vector state = nullptr, scratch = nullptr;
  int state_size = 0;
  CallbackState callbacks;

 protected:
  // The SUNContext of the solver: created with its first problem, kept across problems, freed by
  // this base after the derived class freed its objects in its destructor. Null (and sum says why)
  // when it cannot be created.
  SUNContext ensure_context(IntegratorSummary& sum);

 private:
  struct Context {
    SUNContext ctx = nullptr;
    ~Context() {
      if (ctx) SUNContext_Free(&ctx);
    }
  };
  const SundialsApi& api_;
  Context context_;
};

// The event functions of sys at (t, y) into g, inside a SUNDIALS root callback: an exception is
// kept in `error` for the step loop to rethrow once the solver has returned, and -1 stops the
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

class SundialsIntegrator : public Integrator {
 public:
  SundialsIntegrator(const IntegratorOptions& opts, std::unique_ptr<SundialsSolver> solver);
  // Steps, rejected steps and evaluations of the summary count this call only.
  IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y, StepObserver* observer) override;
  // Applied (tolerances, step bounds, step budget) at the start of the next integrate().
  void set_options(const IntegratorOptions& opts) override { opts_ = opts; }

 private:
  IntegratorSummary run_steps(double t0, double t_end, int num_events, double* y, StepObserver* observer,
                              IntegratorSummary sum);
  IntegratorOptions opts_;
  std::unique_ptr<SundialsSolver> solver_;
};

}  // namespace truss::integrators
