#include "film/adaptive.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace chlorovdb {

std::vector<int> adaptive_sample_counts(const Film& pilot, const AdaptiveSampling& a) {
  if (!(a.target_relative_error > 0) || a.pilot_spp < 2 || a.min_spp < 1 || a.max_spp < a.min_spp)
    throw std::invalid_argument(fmt::format("adaptive_sample_counts: target {}, pilot {} spp, spp range [{}, {}]",
                                            a.target_relative_error, a.pilot_spp, a.min_spp, a.max_spp));
  const int w = pilot.width(), h = pilot.height();
  const PixelRegion r = region_in_film(pilot, a.region, "adaptive_sample_counts");
  const double P = a.pilot_spp;
  std::vector<double> sd(size_t(w) * size_t(h));  // sqrt(v_p)
  for (size_t p = 0; p < sd.size(); ++p) {
    const RGB se = pilot.pixel_standard_error(0, p, P);
    sd[p] = std::sqrt(P * (se.r * se.r + se.g * se.g + se.b * se.b));
  }
  double sum_mean = 0, sum_sd = 0;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const size_t p = size_t(y) * size_t(w) + size_t(x);
      const RGB m = pilot.pixel_mean(0, p, P);
      sum_mean += m.r + m.g + m.b;
      sum_sd += sd[p];
    }
  const double channels = 3.0 * (r.x1 - r.x0) * (r.y1 - r.y0), mean = sum_mean / channels;
  std::vector<int> n(sd.size(), a.max_spp);
  if (!(mean > 0)) return n;
  const double k = sum_sd / (channels * a.target_relative_error * a.target_relative_error * mean * mean);
  for (size_t p = 0; p < sd.size(); ++p)
    n[p] = int(std::clamp(std::ceil(k * sd[p]), double(a.min_spp), double(a.max_spp)));
  return n;
}

}  // namespace chlorovdb
