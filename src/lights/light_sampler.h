#pragma once
// Chooses one light for next-event estimation with a discrete distribution over
// per-light weights: emitted power by default, uniform, or explicit weights over
// a subset (e.g. only the lights that emit in a fluorescence excitation band).
#include <optional>
#include <span>
#include <vector>

#include "core/sampling.h"
#include "lights/light.h"

namespace chlorovdb {

struct SampledLight {
  int index;  // into the scene's light array
  float pmf;
};

class LightSampler {
 public:
  LightSampler() = default;  // empty: sample() returns nothing
  // weights[i] for light i; lights with weight 0 are never chosen. All zero: empty sampler.
  explicit LightSampler(std::span<const float> weights);
  // Only light_indices[k] can be chosen, with probability weights[k] / Σ weights.
  LightSampler(std::span<const int> light_indices, std::span<const float> weights);

  static LightSampler uniform(int light_count);
  // Weights = phi_power over [lambda_min_nm, lambda_max_nm]; call after preprocess().
  static LightSampler power(std::span<const Light> lights, const GeometryScene& scene,
                            float lambda_min_nm = kLambdaMinUV, float lambda_max_nm = kLambdaMax);

  std::optional<SampledLight> sample(float u) const;
  float pmf(int light_index) const;  // 0 for lights outside the sampler's subset
  bool empty() const { return indices_.empty(); }

 private:
  std::vector<int> indices_;          // candidate light indices
  Distribution1D distribution_;       // over indices_
  std::vector<float> pmf_by_light_;   // dense lookup by light index
};

}  // namespace chlorovdb
