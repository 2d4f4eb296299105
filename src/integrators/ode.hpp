// The narrow interface between the integrators and whatever they integrate (after Project
// Chrono's ChIntegrable and Boost.Odeint's system / stepper / observer split): a system gives
// y' = f(t, y) and event functions; an observer sees every accepted step through its dense output.
#pragma once
#include <chrono>
#include <limits>
#include <string>
#include <vector>

namespace truss::integrators {

// The integrators a run can use (scene key run.integrator):
//   dopri54      own explicit Dormand-Prince 5(4) pair (non-stiff)
//   cvode        SUNDIALS CVODE, BDF with Newton iteration and a dense direct solver (stiff)
//   cvode_adams  SUNDIALS CVODE, Adams-Moulton with fixed-point iteration (non-stiff)
//   automatic    dopri54 until Hairer's stiffness test fires, then cvode for the rest of the run
//   ida          SUNDIALS IDA (variable-order BDF on a residual F(t, y, y', z) = 0, banded direct
//                linear solver in the order the DaeForm gives) on the system's DaeForm: the free
//                stack's cross-check solver
//   dop853       own explicit Runge-Kutta pair of order 8 (Hairer's DOP853, non-stiff): fewer
//                steps than dopri54 at tolerances of 1e-7 and tighter
enum class IntegratorKind { dopri54, cvode, cvode_adams, automatic, ida, dop853 };
inline const char* to_string(IntegratorKind k) {
  constexpr const char* names[] = {"dopri54", "cvode", "cvode_adams", "auto", "ida", "dop853"};
  return names[static_cast<int>(k)];
}

// The residual form of the same system for DAE solvers (IDA): the ODE state y (size() values)
// plus num_algebraic() algebraic unknowns z (multipliers), and size() + num_algebraic() residual
// equations F(t, y, y', z) = 0 that the solution of y' = f(t, y) satisfies with the right z.
class DaeForm {
 public:
  virtual ~DaeForm() = default;
  virtual int num_algebraic() const = 0;
  // Returns false if the residual cannot be evaluated (a non-finite value, a bay past straight).
  virtual bool calc_residual(double t, const double* y, const double* yp, const double* z, double* res) = 0;
  // A guess of y' and z at (t, y) for the consistent start (IDACalcIC); false: zeros.
  virtual bool calc_initial_guess(double /*t*/, const double* /*y*/, double* /*yp*/, double* /*z*/) { return false; }
  // An order of the unknowns w = (y, z), and of the residual rows likewise, in which the Jacobian
  // dF/dw + c dF/dw' is banded: order[p] is the index in w of the unknown (and the row) at
  // position p, lower and upper the half-bandwidths. false: no band (the full matrix).
  virtual bool find_band_order(std::vector<int>& /*order*/, int& /*lower*/, int& /*upper*/) const { return false; }
  // For each unknown of w = (y, z) at y, the distance it can move with the residual smooth in it:
  // the scale of the residual's nonlinearity, which a difference-quotient Jacobian must resolve
  // (+inf where nothing limits it). false: none anywhere.
  virtual bool calc_smooth_lengths(const double* /*y*/, double* /*len*/) const { return false; }
  // For each unknown of w = (y, z) at y, the factor f in (0, 1] that scales its error tolerance: a
  // DAE solver accepts an error in w_i up to f_i (rtol |w_i| + atol). Below 1 where w_i carries the
  // configuration only weakly: the state's error then moves the configuration (and the events on
  // it) by 1 / f_i times what the tolerance says. false: 1 everywhere.
  virtual bool calc_error_factors(const double* /*y*/, double* /*f*/) const { return false; }
};

class OdeSystem {
 public:
  // The residual form, or nullptr when the system has none (IDA then refuses it).
  virtual DaeForm* dae_form() { return nullptr; }
  virtual ~OdeSystem() = default;
  virtual int size() const = 0;
  virtual void calc_rhs(double t, const double* y, double* dydt) = 0;
  virtual int num_events() const { return 0; }
  virtual void calc_events(double /*t*/, const double* /*y*/, double* /*g*/) {}
  // +1: only rising zero crossings trigger, -1: only falling, 0: both.
  virtual int event_direction(int /*k*/) const { return 0; }
};

// Continuous solution over the last accepted step [t_begin, t_end].
class DenseOutput {
 public:
  virtual ~DenseOutput() = default;
  virtual void calc_state(double t, double* y) const = 0;
  double t_begin = 0, t_end = 0;
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  // Called after every accepted step (truncated at an event). Return false to stop.
  virtual bool on_step(const DenseOutput& step) = 0;
  // The wall-clock time by which the integration must have stopped (the run's wall-time cap;
  // max(): none). The observer stops it after a step past it; an integrator whose single steps can
  // take long (the SUNDIALS ones: difference-quotient Jacobians, CVODE's dense LU of O(n^3)) also
  // reads it inside the step, stops there and returns IntegratorStatus::deadline.
  virtual std::chrono::steady_clock::time_point deadline() const { return std::chrono::steady_clock::time_point::max(); }
};

struct IntegratorOptions {
  double rtol = 1e-8;         // relative error per step
  double atol = 1e-10;        // absolute error per step, same units as the state
  double initial_step = 0.0;  // 0: chosen by the integrator
  double max_step = std::numeric_limits<double>::infinity();  // cap on the step size
  double fixed_step = 0.0;    // > 0: no error control, constant step (convergence studies)
  long max_steps = 1'000'000; // per call; the run fails with step_limit beyond it
  double event_time_tol = 1e-13;  // absolute tolerance (s) of located event times
  // dopri54, dop853: stop with IntegratorStatus::stiff when Hairer's test (embedded_rk.hpp,
  // StiffnessTest) says the problem has become stiff.
  bool stop_when_stiff = false;
  std::string validate() const;   // empty or "field: reason"
};

enum class IntegratorStatus { reached_end, event, step_limit, stopped_by_observer, failure, stiff, deadline };
const char* to_string(IntegratorStatus);

struct IntegratorSummary {
  IntegratorStatus status = IntegratorStatus::failure;
  std::string message;
  int event_index = -1;   // which event stopped the integration
  double t = 0;           // time reached
  long steps = 0, rejected_steps = 0, rhs_evals = 0;
  std::string to_string() const;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Integrates from t0 towards t_end; y holds the initial state and receives the final one.
  virtual IntegratorSummary integrate(OdeSystem& sys, double t0, double t_end, double* y,
                                      StepObserver* observer) = 0;
  // New options for the next calls (a run changes the step budget between phases); an
  // integrator keeps what it can reuse (last step size, solver memory) across calls.
  virtual void set_options(const IntegratorOptions& opts) = 0;
};

}  // namespace truss::integrators
