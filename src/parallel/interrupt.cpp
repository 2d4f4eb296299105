#include "parallel/interrupt.hpp"

#include <csignal>

namespace truss::parallel {

namespace {
volatile std::sig_atomic_t g_signal = 0;
extern "C" void note_signal(int s) { g_signal = s; }
}  // namespace

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = note_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int interrupt_signal() { return g_signal; }

}  // namespace truss::parallel
