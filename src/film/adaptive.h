#pragma once
// Adaptive sampling for `render --target-error E --adaptive`: samples per pixel
// chosen toward the target from a pilot render, unbiased by construction.
//
// The rule:
//  1. a pilot of P camera samples per pixel (default 16), from its own random
//     streams (pilot_seed), estimates each pixel's per-sample variance
//     v_p = Σ_channels σ²_pc (σ² = P · the pilot's se²) and the region's mean M
//     (over pixels and channels). The pilot is not part of the image.
//  2. the error measure is film/stopping_rule.h's e = sqrt(mean se²) / M over the
//     region's N pixels and 3 channels, se²_pc = σ²_pc / n_p. The fewest samples
//     with Σ_region v_p / n_p = 3 N E² M² are n_p = k sqrt(v_p) (Neyman allocation),
//     k = Σ_region sqrt(v_q) / (3 N E² M²); every film pixel gets n_p = ceil(k sqrt(v_p)),
//     pixels outside a --target-region too (the same error per sample spent);
//  3. n_p is clamped to [min_spp, max_spp]: the floor keeps pixels that were black
//     or flat in the pilot (v_p = 0) from being starved and gives every pixel a
//     standard error; a region whose pilot mean is not positive gets max_spp.
//  4. the image renders exactly n_p fresh samples of pixel p.
// Since n_p is a function of the pilot alone, which is independent of the image's
// samples, each pixel's value is the plain mean of n_p i.i.d. samples given n_p:
// unbiased, with a valid standard error, whatever the pilot's noise. A rule that
// decided on the image's own samples (stop a pixel once its own error looks small)
// is biased: a pixel that has missed a rare bright path looks converged and stops
// low. tests/film measure both.
#include <cstdint>
#include <optional>
#include <vector>

#include "core/rng.h"

#include "film/film.h"
#include "film/stopping_rule.h"

namespace chlorovdb {

struct AdaptiveSampling {
  double target_relative_error = 0;
  std::optional<PixelRegion> region;  // default: the whole film
  int pilot_spp = 16;
  int min_spp = 16;
  int max_spp = 1 << 16;
};

// The seed of the pilot's random streams: independent of `seed`'s image and AOV streams.
constexpr uint64_t pilot_seed(uint64_t seed) { return hash_combine(seed, 0x70696c6f74ULL /* "pilot" */); }

// n_p of every film pixel (y·width + x) from a pilot film holding `pilot_spp`
// samples per pixel. Throws std::invalid_argument for a bad region, target or range.
std::vector<int> adaptive_sample_counts(const Film& pilot, const AdaptiveSampling& a);

}  // namespace chlorovdb
