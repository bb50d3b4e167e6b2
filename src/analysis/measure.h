#pragma once
// `chlorovdb measure`: the mean radiance of a pixel region with a confidence
// interval, as a virtual sensor would report it (a --region, or each of the
// scene's named `sensors`, scene/scene.h).
//
// Batch means: the region is rendered `batches` times over disjoint sample ranges
// (samples [k m, (k + 1) m) of every pixel, m = spp / batches); each batch's region
// mean is one i.i.d. draw, so mean ± t_{K-1} · s / sqrt(K) over the K batch means is
// a confidence interval that needs no assumption about the pixels' correlation or
// the samples' distribution beyond the batch means being near-normal.
//
// Units (what the film records, film/film.h; radiance in the scene's units, W m⁻² sr⁻¹
// when lights are in W):
//  - spectral radiance per band, total layer only: the band-averaged L_λ, W m⁻² sr⁻¹ nm⁻¹;
//  - XYZ per layer: X = ∫ x̄ L_λ dλ / ∫ ȳ dλ (360-830 nm), so Y is the ȳ-weighted mean
//    spectral radiance, W m⁻² sr⁻¹ nm⁻¹ (multiply by 683 lm/W · ∫ȳ dλ ≈ 72 700 for cd/m²);
//  - RGB per layer: linear RGB of that XYZ in the scene's colour space (same unit);
//  - radiance: the sum of the bands × band width, W m⁻² sr⁻¹ over the bands' range.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "checkpoint/partition.h"
#include "scene/scene.h"

namespace chlorovdb {

struct Interval {
  double mean = 0, half_width = 0;  // mean ± half_width at the confidence level
};

struct RegionMeasurement {
  PixelWindow region;
  int spp = 0, batches = 0;
  double confidence = 0.95;
  std::vector<std::string> layers;
  std::vector<std::array<Interval, 3>> xyz, rgb;  // per layer
  std::vector<double> band_centre_nm;
  double band_width_nm = 0;
  std::vector<Interval> spectral;  // per band, total layer
  Interval radiance;               // ∫ over the bands, total layer
};

struct MeasureOptions {
  int spp = 256;
  int batches = 16;     // >= 2; spp is rounded up to a multiple
  int bands = 47;       // over 360-830 nm (10 nm)
  double confidence = 0.95;
  int threads = 0;
  uint64_t seed = 0;
};

// Throws std::invalid_argument for fewer than 2 batches, no bands, or a confidence outside (0, 1).
RegionMeasurement measure_region(const Scene& scene, const PixelWindow& region, const MeasureOptions& options);

// Two-sided Student-t quantile: P(|T_dof| <= t) = confidence (Cornish-Fisher expansion, < 0.5 % off for dof >= 3).
double student_t_quantile(double confidence, int dof);

}  // namespace chlorovdb
