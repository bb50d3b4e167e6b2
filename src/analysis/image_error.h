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
//   reference_variance = mean of se_r^2 over pixels and channels, se_r the reference's own
//              standard-error layer ("<layer>_stderr", film/film.h), 0 when it has none: the
//              measured MSE is the estimate's MSE plus this (independent seeds), so
//              mse - reference_variance estimates the estimate's own MSE;
//   reference_rel_variance = the same term of relMSE: mean of se_r^2 / (r^2 + eps);
//   top_pixel_share = the fraction of the squared error (summed over channels) held by
//              the worst kTopPixelFraction of pixels (at least one): ~0.01-0.02 for
//              Gaussian noise; large when a few pixels (fireflies in the estimate or the
//              reference) dominate the MSE.
//   top_pixel_share_rel = the same for relMSE: the fraction of the sum of
//              (x - r)^2 / (r^2 + eps) held by the worst kTopPixelFraction of pixels (ranked
//              by that sum over their channels). A bright reference firefly dominates MSE but
//              not relMSE; a firefly of the estimate where the reference is dark dominates both.
//   dim_pixel_share_rel = the fraction of relMSE held by the pixels whose reference (the mean
//              of |r| over their channels) is below kDimPixelFraction of the layer's mean: where
//              eps, not r^2, sets the weight, and relMSE weighs an error up to 1 / kRelativeEpsilon
//              times more than in the image's bright parts. The dark set a fluorescent liquid's
//              glow lights through its glass is such a place: its few, rare samples of the
//              liquid can hold most of the layer's relMSE while the liquid itself converges.
// Standard-error layers themselves are not compared.
#include <string>
#include <vector>

#include "io/image.h"

namespace chlorovdb {

// Regularises relMSE where the reference is dark (relative to the layer's mean squared).
inline constexpr double kRelativeEpsilon = 1e-2;
inline constexpr double kTopPixelFraction = 1e-3;
inline constexpr double kDimPixelFraction = 0.1;

// Thresholds of the warnings `converge` and `reference` print (error_warnings).
inline constexpr double kReferenceDominatesShare = 0.1;  // reference_variance > this share of the MSE
inline constexpr double kTopPixelShareWarning = 0.2;     // top 0.1 % of pixels hold more than this

struct LayerError {
  std::string layer;
  double mse = 0, rmse = 0, rel_mse = 0, bias = 0;
  double reference_mean = 0;  // mean of r over pixels and channels (scale of the layer)
  double bias_clamped = 0, reference_mean_clamped = 0;
  double reference_variance = 0, reference_rel_variance = 0;
  double top_pixel_share = 0, top_pixel_share_rel = 0;
  double dim_pixel_share_rel = 0;
};

// The estimate's own error: the measured one minus the reference's own term. With
// independent seeds and an unbiased reference r of the exact image mu,
// E[(x - r)^2] = E[(x - mu)^2] + Var(r) and E[se_r^2] = Var(r), so
// mse - reference_variance is unbiased for the estimate's MSE (variance plus squared
// bias). relMSE weights each pixel by 1 / (r^2 + eps), a function of the noisy r, so
// rel_mse - reference_rel_variance is unbiased only to first order in the reference's
// relative error. Either can come out negative where the reference's term is most of
// the measured error; the ranking is then not trustworthy (relative_error_trustworthy).
double own_mse(const LayerError& e);
double own_rel_mse(const LayerError& e);

// reference_rel_variance / rel_mse: the reference's share of the measured relMSE (0 when rel_mse is 0).
double reference_rel_share(const LayerError& e);

// Whether relMSE (what the benchmarks rank on) measures the estimate: the reference's
// share of it is at most kReferenceDominatesShare and the worst 0.1 % of pixels hold at
// most kTopPixelShareWarning of it.
bool relative_error_trustworthy(const LayerError& e);

// Human-readable warnings for one layer's error: the reference's own error is more
// than kReferenceDominatesShare of the MSE or of relMSE, or the worst 0.1 % of pixels
// hold more than kTopPixelShareWarning of either. Empty when none holds.
std::vector<std::string> error_warnings(const LayerError& e);

// The reference's own error of a layer, from its standard-error layer: the RMS of se
// over pixels and channels, the term it adds to relMSE (as reference_rel_variance),
// and the layer's mean.
struct ReferenceSelfError {
  bool available = false;  // the image has "<layer>_stderr"
  double rms_stderr = 0, rel_mse = 0;
  double mean = 0;
};
ReferenceSelfError reference_self_error(const Image& reference, const std::string& layer);

// One entry per layer present in both images with the same channels (in the
// reference's order); other layers are skipped. Throws std::invalid_argument
// when the sizes differ or no layer is shared.
std::vector<LayerError> image_errors(const Image& estimate, const Image& reference);

// The entry for `layer`, or nullptr.
const LayerError* find_error(const std::vector<LayerError>& errors, const std::string& layer);

}  // namespace chlorovdb
