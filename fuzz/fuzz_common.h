#pragma once
// Shared by the libFuzzer targets: a private scratch folder per process, one thread
// per process, and the rule for what counts as a bug. An InputError is the parser
// doing its job; any other exception escapes to abort() so libFuzzer records the
// input as a crash (as it does for sanitizer reports, signals and time-outs).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <typeinfo>

#include <tbb/global_control.h>
#include <unistd.h>

#include "core/error.h"

namespace chlorovdb::fuzz {

// A folder of our own (removed at exit), so parallel fuzzing jobs never share files.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    std::string templ = (std::filesystem::temp_directory_path() / "chlorovdb_fuzz_XXXXXX").string();
    if (!mkdtemp(templ.data())) {
      std::perror("mkdtemp");
      std::abort();
    }
    static std::filesystem::path to_remove = templ;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(to_remove, ec);
    });
    return std::filesystem::path(templ);
  }();
  return dir;
}

// Every target calls this from LLVMFuzzerInitialize. Worker threads (OpenVDB's parallel
// tools run on TBB) make a unit's coverage depend on scheduling: the same seeds reached
// 8278 counters on CI and 8287 here, and TBB's own functions showed up as "new" coverage
// mid-run, so CI explored inputs a local run with the same seed never reached. The
// threaded paths stay covered by the test suite under the sanitizers (tools/sanitize.sh).
inline void use_one_thread() {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
}

inline std::filesystem::path write_input(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// Runs `body`; InputError is an expected outcome, anything else is a bug.
template <typename F>
int run_expecting_input_errors(const char* what, F&& body) {
  try {
    body();
  } catch (const InputError&) {
    // Rejected with a message: fine.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\n%s: unexpected exception %s: %s\n", what, typeid(e).name(), e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "\n%s: unexpected non-std exception\n", what);
    std::abort();
  }
  return 0;
}

}  // namespace chlorovdb::fuzz
