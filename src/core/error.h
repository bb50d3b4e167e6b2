#pragma once
// User-facing input errors. Every message names where the bad value came from
// (file, key path, value) so a user can fix the input without a debugger.
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace chlorovdb {

class InputError : public std::runtime_error {
 public:
  // e.g. InputError("scenes/a.json", "media.chl.quantum_yield", "1.5", "must be in [0, 1]")
  //   -> "scenes/a.json: media.chl.quantum_yield = 1.5: must be in [0, 1]"
  InputError(std::string_view file, std::string_view key, std::string_view value, std::string_view problem);
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// The candidate closest to `word` by edit distance, for "did you mean" hints;
// empty when nothing is reasonably close.
std::string nearest_word(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace chlorovdb
