#pragma once
// When a progressive render may stop: `render --target-error E` and `--time-limit S`.
//
// Error measure: the relative standard error of a region of the beauty layer,
//   e(n) = sqrt(mean over pixels and channels of se²) / mean over pixels and channels of the value,
// se the standard-error layer (film/film.h): the relative RMS error the image is
// expected to have against the exact image.
//
// The rule, chosen so that stopping does not bias the image:
//  - the error is looked at only when the sample count n is a power of two and
//    n >= min_spp (default 16): few looks (log2 of the cap), each on enough samples
//    for the variance estimate to be meaningful;
//  - the render stops at the first look with e(n) <= target.
// The decision depends on the whole region's variance estimate, not on one pixel:
// its correlation with a pixel's mean is O(1 / pixels), so the stopped image is
// unbiased up to that order, and the estimate of e is itself accurate to about
// 1 / sqrt(2 · pixels · channels) (relative) for well-behaved integrands. Because
// looks are a factor 2 apart in samples, the achieved error is between target/√2
// and target when the rule fires (it is e(n) ≈ c / sqrt(n)); tests/film measure it.
// A time limit stops after the first pass that ends past it (not a look: time
// does not depend on the samples' values).
#include <optional>

#include "film/film.h"

namespace chlorovdb {

struct PixelRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // film pixels [x0, x1) x [y0, y1)
};

struct StoppingRule {
  std::optional<double> target_relative_error;
  std::optional<PixelRegion> region;  // default: the whole film
  int min_spp = 16;
  std::optional<double> time_limit_s;
};

enum class StopReason { none, target_error, time_limit };
const char* to_string(StopReason r);

struct StopDecision {
  StopReason reason = StopReason::none;
  double relative_error = -1;  // e(n) at this look (-1: not looked at)
};

// `region`, or the whole film when empty. Throws std::invalid_argument, naming
// `caller`, for an empty region or one outside the film.
PixelRegion region_in_film(const Film& film, const std::optional<PixelRegion>& region, const char* caller);

// e(n) of layer 0 over `region` (the whole film when empty) with n samples per
// pixel. Infinite when the region's mean is not positive. Throws
// std::invalid_argument for an empty region or one outside the film.
double relative_standard_error(const Film& film, double samples_per_pixel, const std::optional<PixelRegion>& region);

// True when n is a look of the rule: a power of two >= min_spp.
bool is_look(int samples_done, int min_spp);

// Called after each completed pass with the samples done and the seconds rendered.
StopDecision check_stop(const StoppingRule& rule, const Film& film, int samples_done, double seconds);

}  // namespace chlorovdb
