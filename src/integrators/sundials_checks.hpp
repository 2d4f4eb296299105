// Return-flag checks shared by the SUNDIALS integrators (CVODE, IDA), as check_retval in the
// SUNDIALS examples: a failed call makes the integrator summary a failure that names the solver,
// the function and the flag (with the solver's name of it). Each solver file binds its own name
// and flag-name function (CVodeGetReturnFlagName, IDAGetReturnFlagName).
#pragma once
#include <cstdlib>
#include <string>

#include <fmt/format.h>

#include "integrators/ode.hpp"

namespace truss::integrators::sunflags {

// The solver's name of a return flag ("CV_TOO_MUCH_WORK"); SUNDIALS allocates it with malloc.
inline std::string flag_name(char* (*name_of)(long int), int flag) {
  char* name = name_of(flag);
  std::string s = name ? name : "?";
  std::free(name);
  return s;
}

// A negative return flag of a solver function: failure. Returns false on failure.
inline bool check_flag(int flag, const char* solver, char* (*name_of)(long int), const char* function, IntegratorSummary& sum) {
  if (flag >= 0) return true;
  sum.status = IntegratorStatus::failure;
  sum.message = fmt::format("{}: {} failed with flag {} ({})", solver, function, flag, flag_name(name_of, flag));
  return false;
}

// Functions outside the solver (SUNContext_Create: nonzero on failure).
inline bool check_sundials(int flag, const char* solver, const char* function, IntegratorSummary& sum) {
  if (flag == 0) return true;
  sum.status = IntegratorStatus::failure;
  sum.message = fmt::format("{}: {} failed with flag {}", solver, function, flag);
  return false;
}

// Constructors that return a null pointer on failure.
inline bool check_null(const void* p, const char* solver, const char* function, IntegratorSummary& sum) {
  if (p) return true;
  sum.status = IntegratorStatus::failure;
  sum.message = fmt::format("{}: {} returned NULL", solver, function);
  return false;
}

// Error handler that keeps SUNDIALS quiet: every failure reaches the summary through the flags.
inline void silent(int, const char*, const char*, char*, void*) {}

}  // namespace truss::integrators::sunflags
