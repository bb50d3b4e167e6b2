#include "analysis/image_error.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include <fmt/format.h>

#include "film/film.h"

namespace chlorovdb {

namespace {

// The fraction of `total` held by the largest kTopPixelFraction of `per_pixel` (at least one).
double top_share(std::vector<double>& per_pixel, double total) {
  const size_t top = std::max<size_t>(1, size_t(std::ceil(kTopPixelFraction * double(per_pixel.size()))));
  std::nth_element(per_pixel.begin(), per_pixel.begin() + (top - 1), per_pixel.end(), std::greater<double>());
  double worst = 0;
  for (size_t i = 0; i < top; ++i) worst += per_pixel[i];
  return worst / total;
}

LayerError layer_error(const ImageLayer& x, const ImageLayer& r, const ImageLayer* r_stderr) {
  LayerError e;
  e.layer = r.name;
  const size_t n = r.pixels.size();
  double sum_r = 0;
  for (float v : r.pixels) sum_r += v;
  e.reference_mean = n ? sum_r / double(n) : 0.0;
  const double eps = std::max(kRelativeEpsilon * e.reference_mean * e.reference_mean, 1e-30);
  double se = 0, rel = 0, diff = 0;
  for (size_t i = 0; i < n; ++i) {
    const double d = double(x.pixels[i]) - double(r.pixels[i]);
    se += d * d;
    rel += d * d / (double(r.pixels[i]) * r.pixels[i] + eps);
    diff += d;
  }
  if (n) {
    e.mse = se / double(n);
    e.rel_mse = rel / double(n);
    e.bias = diff / double(n);
  }
  e.rmse = std::sqrt(e.mse);
  if (r_stderr && r_stderr->pixels.size() == n && n) {
    double var = 0, rel_var = 0;
    for (size_t i = 0; i < n; ++i) {
      const double s2 = double(r_stderr->pixels[i]) * r_stderr->pixels[i];
      var += s2;
      rel_var += s2 / (double(r.pixels[i]) * r.pixels[i] + eps);
    }
    e.reference_variance = var / double(n);
    e.reference_rel_variance = rel_var / double(n);
  }
  if (const size_t nc = r.channels.size(); n && nc && se > 0) {
    std::vector<double> per_pixel(n / nc, 0.0), per_pixel_rel(n / nc, 0.0), magnitude(n / nc, 0.0);
    for (size_t i = 0; i < n; ++i) {
      const double d = double(x.pixels[i]) - double(r.pixels[i]);
      per_pixel[i / nc] += d * d;
      per_pixel_rel[i / nc] += d * d / (double(r.pixels[i]) * r.pixels[i] + eps);
      magnitude[i / nc] += std::abs(double(r.pixels[i])) / double(nc);
    }
    double dim = 0;
    for (size_t p = 0; p < per_pixel_rel.size(); ++p)
      if (magnitude[p] < kDimPixelFraction * std::abs(e.reference_mean)) dim += per_pixel_rel[p];
    e.dim_pixel_share_rel = rel > 0 ? dim / rel : 0.0;
    e.top_pixel_share = top_share(per_pixel, se);
    e.top_pixel_share_rel = top_share(per_pixel_rel, rel);
  }
  if (n) {
    std::vector<float> magnitude(n);
    for (size_t i = 0; i < n; ++i) magnitude[i] = std::abs(r.pixels[i]);
    const size_t k = std::min(n - 1, size_t(0.999 * double(n)));
    std::nth_element(magnitude.begin(), magnitude.begin() + k, magnitude.end());
    const double q = magnitude[k];
    double sum_x = 0, sum_rc = 0;
    for (size_t i = 0; i < n; ++i) {
      sum_x += std::clamp(double(x.pixels[i]), -q, q);
      sum_rc += std::clamp(double(r.pixels[i]), -q, q);
    }
    e.bias_clamped = (sum_x - sum_rc) / double(n);
    e.reference_mean_clamped = sum_rc / double(n);
  }
  return e;
}

}  // namespace

std::vector<LayerError> image_errors(const Image& estimate, const Image& reference) {
  if (estimate.width != reference.width || estimate.height != reference.height)
    throw std::invalid_argument(fmt::format("image sizes differ: {}x{} against a {}x{} reference", estimate.width,
                                            estimate.height, reference.width, reference.height));
  std::vector<LayerError> errors;
  for (const ImageLayer& r : reference.layers) {
    const ImageLayer* x = estimate.find_layer(r.name);
    if (is_stderr_layer(r.name) || is_aov_layer(r.name) || !x || x->channels != r.channels || x->pixels.size() != r.pixels.size()) continue;
    const ImageLayer* r_stderr = reference.find_layer(stderr_layer_name(r.name));
    if (r_stderr && r_stderr->channels != r.channels) r_stderr = nullptr;
    errors.push_back(layer_error(*x, r, r_stderr));
  }
  if (errors.empty()) throw std::invalid_argument("the image and the reference share no layer");
  return errors;
}

double own_mse(const LayerError& e) { return e.mse - e.reference_variance; }
double own_rel_mse(const LayerError& e) { return e.rel_mse - e.reference_rel_variance; }

double reference_rel_share(const LayerError& e) { return e.rel_mse > 0 ? e.reference_rel_variance / e.rel_mse : 0.0; }

bool relative_error_trustworthy(const LayerError& e) {
  return reference_rel_share(e) <= kReferenceDominatesShare && e.top_pixel_share_rel <= kTopPixelShareWarning;
}

std::vector<std::string> error_warnings(const LayerError& e) {
  std::vector<std::string> w;
  const double mse_share = e.mse > 0 ? e.reference_variance / e.mse : 0.0;
  if (mse_share > kReferenceDominatesShare || reference_rel_share(e) > kReferenceDominatesShare)
    w.push_back(fmt::format("layer {}: the reference's own error is {:.0f} % of the MSE ({:.3e} of {:.3e}) and {:.0f} % of relMSE "
                            "({:.3e} of {:.3e}): render the reference longer, or compare with mse - reference_variance",
                            e.layer, 100 * mse_share, e.reference_variance, e.mse, 100 * reference_rel_share(e),
                            e.reference_rel_variance, e.rel_mse));
  if (e.top_pixel_share > kTopPixelShareWarning || e.top_pixel_share_rel > kTopPixelShareWarning)
    w.push_back(fmt::format("layer {}: the worst {:g} % of pixels hold {:.0f} % of the squared error and {:.0f} % of relMSE "
                            "(fireflies in the estimate or the reference?): those errors are dominated by them; compare "
                            "bias_clamped, and several seeds",
                            e.layer, 100 * kTopPixelFraction, 100 * e.top_pixel_share, 100 * e.top_pixel_share_rel));
  return w;
}

ReferenceSelfError reference_self_error(const Image& reference, const std::string& layer) {
  ReferenceSelfError out;
  const ImageLayer* r = reference.find_layer(layer);
  const ImageLayer* se = reference.find_layer(stderr_layer_name(layer));
  if (!r || !se || se->pixels.size() != r->pixels.size() || r->pixels.empty()) return out;
  out.available = true;
  const size_t n = r->pixels.size();
  double sum_r = 0, var = 0, rel = 0;
  for (float v : r->pixels) sum_r += v;
  out.mean = sum_r / double(n);
  const double eps = std::max(kRelativeEpsilon * out.mean * out.mean, 1e-30);
  for (size_t i = 0; i < n; ++i) {
    const double s2 = double(se->pixels[i]) * se->pixels[i];
    var += s2;
    rel += s2 / (double(r->pixels[i]) * r->pixels[i] + eps);
  }
  out.rms_stderr = std::sqrt(var / double(n));
  out.rel_mse = rel / double(n);
  return out;
}

const LayerError* find_error(const std::vector<LayerError>& errors, const std::string& layer) {
  for (const LayerError& e : errors)
    if (e.layer == layer) return &e;
  return nullptr;
}

}  // namespace chlorovdb
