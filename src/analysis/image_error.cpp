#include "analysis/image_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace chlorovdb {

namespace {

LayerError layer_error(const ImageLayer& x, const ImageLayer& r) {
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
    if (!x || x->channels != r.channels || x->pixels.size() != r.pixels.size()) continue;
    errors.push_back(layer_error(*x, r));
  }
  if (errors.empty()) throw std::invalid_argument("the image and the reference share no layer");
  return errors;
}

const LayerError* find_error(const std::vector<LayerError>& errors, const std::string& layer) {
  for (const LayerError& e : errors)
    if (e.layer == layer) return &e;
  return nullptr;
}

}  // namespace chlorovdb
