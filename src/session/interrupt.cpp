#include "session/interrupt.h"

#include <csignal>
#include <unistd.h>

namespace chlorovdb {

namespace {

std::atomic<bool> g_interrupt{false};

extern "C" void on_interrupt(int) {
  // A second Ctrl-C means "now": leave without writing.
  if (g_interrupt.exchange(true)) _exit(130);
}

}  // namespace

std::atomic<bool>& interrupt_requested() { return g_interrupt; }

InterruptScope::InterruptScope() {
  g_interrupt = false;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

InterruptScope::~InterruptScope() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

}  // namespace chlorovdb
