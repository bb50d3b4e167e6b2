#pragma once
// Ctrl-C and SIGTERM for every long computation of the CLI (render, reference,
// converge): while an InterruptScope lives, the first signal sets
// interrupt_requested() (the computation stops after its current tiles and
// still writes what it has); a second one exits at once with status 130.
#include <atomic>

namespace chlorovdb {

class InterruptScope {
 public:
  InterruptScope();   // clears the flag, installs the handler
  ~InterruptScope();  // restores the default handlers
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

// Set by the handler; the renderer polls it between tiles.
std::atomic<bool>& interrupt_requested();

}  // namespace chlorovdb
