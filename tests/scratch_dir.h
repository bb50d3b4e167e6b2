#pragma once
// A scratch folder per test process, removed when the process exits. ctest runs the
// tests in parallel, one process each; fixed file names in one shared folder raced
// (two tests writing bad.json at once made a third read the other's scene).
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace chlorovdb::test {

inline std::filesystem::path scratch_dir(const std::string& suite) {
  static std::vector<std::filesystem::path> made;
  static const bool cleanup_registered = [] {
    return std::atexit([] {
      std::error_code ec;
      for (const auto& dir : made) std::filesystem::remove_all(dir, ec);
    }) == 0;
  }();
  (void)cleanup_registered;
  const auto dir =
      std::filesystem::temp_directory_path() / ("chlorovdb_" + suite + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  if (std::find(made.begin(), made.end(), dir) == made.end()) made.push_back(dir);
  return dir;
}

}  // namespace chlorovdb::test
