#include "fluorescence/redistribution.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

RedistributionWeight::RedistributionWeight(Redistribution kind, const Spectrum& emission) : kind_(kind) {
  if (kind_ == Redistribution::kasha_vavilov) return;
  lambda_min_ = kLambdaMinUV;
  step_ = 0.25f;
  const int n = int((kLambdaMax - kLambdaMinUV) / step_) + 1;
  tail_.assign(n, 0.f);
  const float total = emission.integral(kLambdaMinUV, kLambdaMax);
  for (int i = 0; i < n; ++i)
    tail_[i] = total > 0.f ? emission.integral(lambda_min_ + i * step_, kLambdaMax) / total : 0.f;
}

float RedistributionWeight::emission_above(float lambda) const {
  if (tail_.empty()) return 1.f;
  const float x = (lambda - lambda_min_) / step_;
  if (x <= 0.f) return tail_.front();
  const int i = int(x);
  if (i >= int(tail_.size()) - 1) return tail_.back();
  const float f = x - i;
  return (1 - f) * tail_[i] + f * tail_[i + 1];
}

}  // namespace chlorovdb
