#include "integrator/continuation_guide_training.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>

#include <tbb/parallel_for.h>

#include "integrator/fluorescence_event.h"
#include "integrator/medium_region.h"
#include "integrator/transport.h"

namespace chlorovdb {

namespace {

ContinuationGuide train_medium(const Scene& scene, int medium, const GuideTraining& training) {
  const auto& pigments = scene.fluorescence[size_t(medium)];
  const Bounds3 region = medium_region(scene, medium);
  if (pigments.empty() || region.empty()) return {};
  const std::array<int, 3> n = cell_counts(region, std::max(1, training.cells_per_axis));
  const int cells = n[0] * n[1] * n[2];
  const Vec3 cell_size{region.diagonal().x / n[0], region.diagonal().y / n[1], region.diagonal().z / n[2]};
  std::vector<std::vector<float>> weights(static_cast<size_t>(cells));

  tbb::parallel_for(0, cells, [&](int cell) {
    Rng rng(hash_combine(hash_combine(training.seed, uint64_t(medium)), uint64_t(cell)), mix_bits(training.seed));
    const int ix = cell % n[0], iy = (cell / n[0]) % n[1], iz = cell / (n[0] * n[1]);
    const Vec3 lo = region.lo + Vec3{ix * cell_size.x, iy * cell_size.y, iz * cell_size.z};
    std::vector<float> w(size_t(kDirectionBins), 0.f);
    PathStats stats;
    SampledWavelengths any_lambda = SampledWavelengths::single(550.f);
    PreparedMedia media(scene, any_lambda);
    int origins = 0;
    for (int attempt = 0; attempt < 8 * training.points_per_cell && origins < training.points_per_cell; ++attempt) {
      const Vec3 x = lo + Vec3{rng.uniform() * cell_size.x, rng.uniform() * cell_size.y, rng.uniform() * cell_size.z};
      if (medium_at(scene, x) != medium) continue;
      const MediumProperties mp = sample_point(scene.media[size_t(medium)], x, media[medium]);
      bool pigment_here = false;
      for (const FluorescentPigment& fp : pigments) pigment_here |= mp.concentration[size_t(fp.pigment)] > 0.f;
      if (!pigment_here) continue;
      ++origins;
      for (int bin = 0; bin < kDirectionBins; ++bin)
        for (int k = 0; k < training.probes_per_bin; ++k) {
          const auto p = std::min(size_t(rng.uniform() * pigments.size()), pigments.size() - 1);
          const FluorescentPigment& fp = pigments[p];
          float pdf_lambda;
          const float lp = sample_continuation_wavelength(fp, rng, &pdf_lambda);
          const float eps = fp.epsilon(lp);
          const Vec3 dir = direction_in_bin(bin, Point2{rng.uniform(), rng.uniform()});
          if (eps == 0.f || !(pdf_lambda > 0.f)) continue;
          const ContinuationOrigin origin{x, medium, &fp, continuation_probability(0, 0)};
          const float L = continuation_radiance(scene, origin, dir, lp, rng, stats, 0);
          const float v = lp * eps * L / pdf_lambda;
          if (std::isfinite(v) && v > 0.f) w[size_t(bin)] += v * v;
        }
    }
    // The root mean square of a bin's returns: the density that minimises the
    // variance of a noisy integrand is ∝ √E[v²], not E[v].
    for (float& v : w) v = std::sqrt(v);
    weights[size_t(cell)] = std::move(w);
  });

  // Each cell's histogram as a distribution, plus a quarter of the medium's mean one.
  std::vector<double> mean(size_t(kDirectionBins), 0.0);
  int learned = 0;
  for (auto& w : weights) {
    double total = 0;
    for (float v : w) total += v;
    if (!(total > 0)) {
      std::fill(w.begin(), w.end(), 0.f);
      continue;
    }
    for (float& v : w) v = float(v / total);
    for (size_t b = 0; b < w.size(); ++b) mean[b] += w[b];
    ++learned;
  }
  if (learned == 0) return {};
  for (auto& w : weights)
    for (size_t b = 0; b < w.size(); ++b) w[b] += float(0.25 * mean[b] / learned);
  return ContinuationGuide(region, n, weights, training.uniform_share);
}

}  // namespace

std::vector<ContinuationGuide> train_continuation_guides(const Scene& scene, const GuideTraining& training) {
  std::vector<ContinuationGuide> guides(scene.media.size());
  for (size_t m = 0; m < scene.media.size(); ++m) guides[m] = train_medium(scene, int(m), training);
  return guides;
}

bool uses_continuation_guides(const Scene& scene) {
  return scene.settings.fluorescence == FluorescenceMode::full &&
         scene.settings.continuation_directions == ContinuationDirections::guided && scene.has_fluorescence();
}

double prepare_continuation_guides(const Scene& scene) {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  if (scene.continuation_guides || !uses_continuation_guides(scene)) return 0.0;
  const auto start = std::chrono::steady_clock::now();
  scene.continuation_guides = std::make_shared<const std::vector<ContinuationGuide>>(train_continuation_guides(scene));
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace chlorovdb
