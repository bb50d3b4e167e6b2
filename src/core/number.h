#pragma once
// The one check every number from a user goes through (scene keys through
// ParamReader, command-line options through cli/options.h): a value must be
// finite, fit the type it is stored in and lie in its documented range.
// Limits shared by the scene file and the command line live here too, so the
// two cannot drift apart.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace chlorovdb {

// Largest magnitude a float parameter may have: below FLT_MAX with room for
// the unit conversions (length_unit, µM -> M) applied after reading.
inline constexpr double kMaxFloatParam = 3e38;
inline constexpr int kMaxImageSide = 65536;   // render.resolution, --resolution
inline constexpr int kMaxSpp = 1 << 24;       // render.spp, --spp
inline constexpr int kMaxThreads = 1024;      // --threads

// Why `v` is not a usable value in [lo, hi]: "must be finite", "must be >= 0",
// "must be in [1, 65536]"; nullopt when it is. A range end at ±kMaxFloatParam
// (or beyond) is left out of the message.
std::optional<std::string> range_problem(double v, double lo, double hi);

// Strict parses of a whole command-line word: no sign on unsigned types, no
// trailing characters, no wrap-around ("-1" or "18446744073709551616" are not a
// uint64). nullopt when `text` is not such a number.
std::optional<int64_t> parse_int64(std::string_view text);
std::optional<uint64_t> parse_uint64(std::string_view text);
// Any finite double ("nan", "inf" and overflow such as "1e400" are refused).
std::optional<double> parse_finite_double(std::string_view text);

}  // namespace chlorovdb
