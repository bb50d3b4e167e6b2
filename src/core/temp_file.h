#pragma once
// The temporary an output file is written to before it is renamed over the
// target: in the target's folder (rename is atomic only within a file system)
// and unique per process and per call, so concurrent writers of one path, in
// one process or several, never share a temporary.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <unistd.h>

#include <fmt/format.h>

namespace chlorovdb {

inline std::filesystem::path temporary_beside(const std::filesystem::path& target) {
  static std::atomic<uint64_t> calls{0};
  return fmt::format("{}.{}.{}.tmp", target.string(), ::getpid(), calls.fetch_add(1));
}

}  // namespace chlorovdb
