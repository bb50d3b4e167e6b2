#include "core/sampling.h"

#include <stdexcept>

namespace chlorovdb {

Distribution1D::Distribution1D(std::span<const float> weights) {
  const size_t n = weights.size();
  pdf_.resize(n);
  cdf_.resize(n + 1);
  cdf_[0] = 0;
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!(weights[i] >= 0.f) || !std::isfinite(weights[i]))
      throw std::invalid_argument("Distribution1D: weights must be finite and non-negative");
    sum += weights[i];
  }
  total_ = float(sum);
  double acc = 0;
  for (size_t i = 0; i < n; ++i) {
    pdf_[i] = sum > 0 ? float(weights[i] / sum) : 1.f / float(n);
    acc += sum > 0 ? weights[i] / sum : 1.0 / double(n);
    cdf_[i + 1] = acc;
  }
  if (n) cdf_[n] = 1.f;
  guide_.resize(n);
  for (size_t k = 0, i = 0; k < n; ++k) {
    const double u = double(k) / double(n);
    while (i + 1 < n && cdf_[i + 1] <= u) ++i;
    guide_[k] = uint32_t(i);
  }
}

}  // namespace chlorovdb
