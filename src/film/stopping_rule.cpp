#include "film/stopping_rule.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace chlorovdb {

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::none: return "none";
    case StopReason::target_error: return "target error reached";
    case StopReason::time_limit: return "time limit reached";
  }
  return "?";
}

PixelRegion region_in_film(const Film& film, const std::optional<PixelRegion>& region, const char* caller) {
  const PixelRegion r = region.value_or(PixelRegion{0, 0, film.width(), film.height()});
  if (r.x0 < 0 || r.y0 < 0 || r.x1 > film.width() || r.y1 > film.height() || r.x0 >= r.x1 || r.y0 >= r.y1)
    throw std::invalid_argument(fmt::format("{}: region {},{},{},{} is empty or outside the {}x{} film", caller, r.x0, r.y0,
                                            r.x1, r.y1, film.width(), film.height()));
  return r;
}

double relative_standard_error(const Film& film, double n, const std::optional<PixelRegion>& region) {
  const PixelRegion r = region_in_film(film, region, "relative_standard_error");
  double sum_mean = 0, sum_var = 0;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const size_t p = size_t(y) * size_t(film.width()) + size_t(x);
      const RGB m = film.pixel_mean(0, p, n), se = film.pixel_standard_error(0, p, n);
      sum_mean += m.r + m.g + m.b;
      sum_var += se.r * se.r + se.g * se.g + se.b * se.b;
    }
  const double count = 3.0 * (r.x1 - r.x0) * (r.y1 - r.y0);
  if (!(sum_mean > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(sum_var / count) / (sum_mean / count);
}

bool is_look(int n, int min_spp) { return n >= min_spp && n > 0 && (n & (n - 1)) == 0; }

StopDecision check_stop(const StoppingRule& rule, const Film& film, int samples_done, double seconds) {
  StopDecision d;
  if (rule.target_relative_error && is_look(samples_done, rule.min_spp)) {
    d.relative_error = relative_standard_error(film, samples_done, rule.region);
    if (d.relative_error <= *rule.target_relative_error) {
      d.reason = StopReason::target_error;
      return d;
    }
  }
  if (rule.time_limit_s && seconds >= *rule.time_limit_s) d.reason = StopReason::time_limit;
  return d;
}

}  // namespace chlorovdb
