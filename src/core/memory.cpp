#include "core/memory.h"

#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {

int64_t available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream fields(line.substr(13));
      int64_t kb = 0;
      if (fields >> kb) return kb * 1024;
    }
  return 0;
}

void check_memory(double bytes, std::string_view what, std::string_view file, std::string_view key,
                  std::string_view value) {
  const int64_t available = available_memory_bytes();
  if (available <= 0 || bytes <= double(available)) return;  // unknown availability: let the allocator decide
  constexpr double GiB = 1024.0 * 1024.0 * 1024.0;
  throw InputError(file, key, value,
                   fmt::format("needs about {:.3g} GiB for {}, but only {:.3g} GiB are available", bytes / GiB, what,
                               double(available) / GiB));
}

}  // namespace chlorovdb
