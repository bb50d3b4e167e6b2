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
}

int Distribution1D::sample(float u, float* pmf, float* u_remapped) const {
  // First index whose upper edge exceeds u; skip zero-probability bins.
  const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u);
  int i = std::clamp(int(it - cdf_.begin()) - 1, 0, int(pdf_.size()) - 1);
  while (pdf_[i] == 0.f && i > 0) --i;
  if (pmf) *pmf = pdf_[i];
  if (u_remapped) {
    const double width = cdf_[i + 1] - cdf_[i];
    *u_remapped = width > 0 ? std::min(float((u - cdf_[i]) / width), 0x1.fffffep-1f) : 0.f;
  }
  return i;
}

}  // namespace chlorovdb
