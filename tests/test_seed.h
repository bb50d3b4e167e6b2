#pragma once
// Seeds for the tests' random numbers. Every test fixes its seeds, so a run is
// repeatable; CHLOROVDB_TEST_SEED_OFFSET=K (K > 0) moves all of them at once, so that
// tools/seed_sweep.sh can run the suite under many seeds and find a statistical test
// that passes only by the luck of its seed (sessions 4-5 found two). A sound 4-sigma
// check fails on about 1 seed in 16 000.
#include <cstdint>
#include <cstdlib>

namespace chlorovdb::test {

inline uint64_t test_seed(uint64_t seed) {
  static const uint64_t offset = [] {
    const char* s = std::getenv("CHLOROVDB_TEST_SEED_OFFSET");
    return s ? std::strtoull(s, nullptr, 10) : 0ull;
  }();
  // A large odd stride: shifted seeds of one test never land on another's.
  return seed + offset * 0x9e3779b97f4a7c15ull;
}

}  // namespace chlorovdb::test
