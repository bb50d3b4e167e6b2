#pragma once
// Checks for numeric command-line options, shared by every subcommand (and
// `voxelize`). CLI11 converts words with strtoull / strtold, which accept "-1"
// for an unsigned (it wraps), saturate 2^64 and read "nan" and "inf", and its
// Range lets NaN through. These validators see the word before conversion and
// apply the scene file's check (core/number.h): the whole word must be a
// finite number that fits the option's type and range.
#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "core/number.h"
#include "spectra/sampled.h"  // kMaxWavelengths

namespace chlorovdb::cli {

// A whole number in [lo, hi] (int options: pass the int range or narrower).
inline CLI::Validator Integer(int64_t lo, int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& word) -> std::string {
        const auto v = parse_int64(word);
        if (!v || *v < lo || *v > hi) return fmt::format("{}: expected a whole number in [{}, {}]", word, lo, hi);
        return {};
      },
      fmt::format("INT in [{}, {}]", lo, hi));
}

// A whole number in [0, 2^64 - 1] (seeds).
inline const CLI::Validator Unsigned64(
    [](std::string& word) -> std::string {
      if (!parse_uint64(word)) return fmt::format("{}: expected a whole number in [0, {}]", word, UINT64_MAX);
      return {};
    },
    "UINT64");

// A finite real number in [lo, hi]; the range ends need not be float-exact.
inline CLI::Validator Real(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& word) -> std::string {
        const auto v = parse_finite_double(word);
        if (!v) return fmt::format("{}: expected a finite number", word);
        if (const auto problem = range_problem(*v, lo, hi)) return fmt::format("{}: {}", word, *problem);
        return {};
      },
      "NUMBER");
}

}  // namespace chlorovdb::cli
