#include "fluorescence/excitation_sampler.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

ExcitationSampler::ExcitationSampler(const Spectrum& light, const Spectrum& epsilon, ExcitationSampling mode,
                                     float lambda_min, float lambda_max, float bin_nm)
    : mode_(mode), lambda_min_(lambda_min), bin_nm_(bin_nm) {
  const int n = std::max(1, int(std::ceil((lambda_max - lambda_min) / bin_nm)));
  std::vector<float> weight(n);
  double total = 0;
  constexpr int kSub = 8;  // sub-samples per bin: tables are as fine as 0.19 nm
  for (int b = 0; b < n; ++b) {
    double sum = 0, peak = 0;
    for (int s = 0; s < kSub; ++s) {
      const float la = lambda_min + (b + (s + 0.5f) / kSub) * bin_nm;
      const double g = double(light(la)) * epsilon(la) * la;
      sum += g;
      peak = std::max(peak, g);
    }
    const double mean = sum / kSub;
    total += mean * bin_nm;
    // A bin where the integrand is anywhere positive must keep a positive pdf,
    // or the estimator would be biased; peak/kSub is a floor that guarantees it.
    weight[b] = float(std::max(mean, peak / kSub));
  }
  total_ = float(total);
  if (!(total_ > 0.f)) return;
  bins_ = Distribution1D(weight);
  int first = 0, last = n - 1;
  while (first < n && !(weight[first] > 0.f)) ++first;
  while (last > first && !(weight[last] > 0.f)) --last;
  support_min_ = float(lambda_min + double(first) * bin_nm);
  support_max_ = float(lambda_min + double(last + 1) * bin_nm);
  uniform_pdf_ = float(1.0 / (double(support_max_) - double(support_min_)));
}

float ExcitationSampler::sample(float u, float* pdf) const {
  if (mode_ == ExcitationSampling::uniform) {
    *pdf = uniform_pdf_;
    const float lambda = float(support_min_ + double(u) * (double(support_max_) - double(support_min_)));
    return std::clamp(lambda, support_min_, std::nextafter(support_max_, support_min_));
  }
  float pmf, u_in;
  const int b = bins_.sample(u, &pmf, &u_in);
  *pdf = pmf / bin_nm_;
  // In double, and kept strictly inside bin b: in float, b + u_in rounds up to
  // b + 1 for u_in near 1, and pdf() would then read the neighbouring bin.
  const double lo = lambda_min_ + double(b) * bin_nm_;
  const float lambda = float(lo + double(u_in) * bin_nm_);
  return std::clamp(lambda, float(lo), std::nextafter(float(lo + bin_nm_), float(lo)));
}

float ExcitationSampler::pdf(float lambda) const {
  if (mode_ == ExcitationSampling::uniform)
    return lambda >= support_min_ && lambda < support_max_ ? uniform_pdf_ : 0.f;
  const int b = int(std::floor((double(lambda) - lambda_min_) / bin_nm_));
  if (b < 0 || b >= bins_.size()) return 0.f;
  return bins_.pmf(b) / bin_nm_;
}

float excitation_pdf(const ExcitationSampler& es, float lambda) {
  return es.can_excite() ? es.pdf(lambda) : 1.f / (kLambdaMax - kLambdaMinUV);
}

float sample_excitation(const ExcitationSampler& es, float u, float* pdf) {
  if (es.can_excite()) return es.sample(u, pdf);
  *pdf = 1.f / (kLambdaMax - kLambdaMinUV);
  return kLambdaMinUV + u * (kLambdaMax - kLambdaMinUV);
}

}  // namespace chlorovdb
