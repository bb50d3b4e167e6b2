#include "core/number.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

namespace chlorovdb {

std::optional<std::string> range_problem(double v, double lo, double hi) {
  if (!std::isfinite(v)) return "must be finite";
  if (v >= lo && v <= hi) return std::nullopt;
  if ((v > hi && hi >= kMaxFloatParam) || (v < lo && lo <= -kMaxFloatParam))
    return fmt::format("must lie within ±{:g} (single precision)", kMaxFloatParam);
  if (hi >= kMaxFloatParam) return fmt::format("must be >= {:g}", lo);
  if (lo <= -kMaxFloatParam) return fmt::format("must be <= {:g}", hi);
  return fmt::format("must be in [{:g}, {:g}]", lo, hi);
}

namespace {

template <class T>
std::optional<T> parse_whole(std::string_view text) {
  T v{};
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc() || ptr != end || text.empty()) return std::nullopt;
  return v;
}

}  // namespace

std::optional<int64_t> parse_int64(std::string_view text) {
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  return parse_whole<int64_t>(text);
}

std::optional<uint64_t> parse_uint64(std::string_view text) {
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  return parse_whole<uint64_t>(text);
}

std::optional<double> parse_finite_double(std::string_view text) {
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  const auto v = parse_whole<double>(text);
  if (!v || !std::isfinite(*v)) return std::nullopt;
  return v;
}

}  // namespace chlorovdb
