// SIGINT and SIGTERM (Ctrl-C, and what mpirun sends every rank when it gets one): a handler that
// only notes the signal; every rank's engine looks at it between runs and leaves with Interrupted,
// and truss-campaign's main path keeps what is done (docs/campaigns.md, "Resuming").
#pragma once
#include <stdexcept>

namespace truss::parallel {

struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("interrupted") {}
};

void install_interrupt_handlers();
int interrupt_signal();  // the signal received, 0 if none
inline bool interrupted() { return interrupt_signal() != 0; }

}  // namespace truss::parallel
