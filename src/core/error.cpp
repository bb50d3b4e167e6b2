#include "core/error.h"

#include <algorithm>
#include <fmt/format.h>

namespace chlorovdb {

static std::string compose(std::string_view file, std::string_view key, std::string_view value,
                           std::string_view problem) {
  std::string msg(file);
  if (!key.empty()) msg += fmt::format(": {}", key);
  if (!value.empty()) msg += fmt::format(" = {}", value);
  msg += fmt::format(": {}", problem);
  return msg;
}

InputError::InputError(std::string_view file, std::string_view key, std::string_view value,
                       std::string_view problem)
    : std::runtime_error(compose(file, key, value, problem)) {}

static size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string nearest_word(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = SIZE_MAX;
  for (const auto& c : candidates) {
    const size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  // Accept up to about a third of the word mistyped.
  return best_d <= std::max<size_t>(2, word.size() / 3) ? best : std::string();
}

}  // namespace chlorovdb
