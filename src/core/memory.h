#pragma once
// Memory the machine can still give us, and a check that refuses an
// allocation, with its estimate, before making it.
#include <cstdint>
#include <string>
#include <string_view>

namespace chlorovdb {

// MemAvailable from /proc/meminfo, in bytes (0 when it cannot be read).
int64_t available_memory_bytes();

// Throws InputError(file, key, value, "needs ~X GiB for <what>, Y GiB available")
// when `bytes` (an estimate, may be astronomically large) exceeds what is available.
void check_memory(double bytes, std::string_view what, std::string_view file, std::string_view key,
                  std::string_view value);

}  // namespace chlorovdb
