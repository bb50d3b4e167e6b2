#pragma once
// Error of a rendered image against a reference, per layer: what `chlorovdb
// converge` and the benchmarks report.
//
//   MSE      = mean over pixels and channels of (x - r)^2
//   RMSE     = sqrt(MSE)
//   relMSE   = mean of (x - r)^2 / (r^2 + eps), eps = kRelativeEpsilon * mean(r)^2 over the layer,
//              so the metric does not depend on the image's arbitrary radiance scale
//   bias     = mean of (x - r): a signed check that is ~0 for an unbiased estimator
//   bias_clamped = the same with x and r clamped to +-q, q the 99.9th percentile of |r| over the
//              layer: a reference that is not converged in a few pixels (fireflies: rare, very
//              bright samples) moves `bias` and MSE by its outliers alone; this does not.
#include <string>
#include <vector>

#include "io/image.h"

namespace chlorovdb {

// Regularises relMSE where the reference is dark (relative to the layer's mean squared).
inline constexpr double kRelativeEpsilon = 1e-2;

struct LayerError {
  std::string layer;
  double mse = 0, rmse = 0, rel_mse = 0, bias = 0;
  double reference_mean = 0;  // mean of r over pixels and channels (scale of the layer)
  double bias_clamped = 0, reference_mean_clamped = 0;
};

// One entry per layer present in both images with the same channels (in the
// reference's order); other layers are skipped. Throws std::invalid_argument
// when the sizes differ or no layer is shared.
std::vector<LayerError> image_errors(const Image& estimate, const Image& reference);

// The entry for `layer`, or nullptr.
const LayerError* find_error(const std::vector<LayerError>& errors, const std::string& layer);

}  // namespace chlorovdb
