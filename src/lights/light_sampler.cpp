#include "lights/light_sampler.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace chlorovdb {

LightSampler::LightSampler(std::span<const float> weights) {
  std::vector<int> all(weights.size());
  std::iota(all.begin(), all.end(), 0);
  *this = LightSampler(all, weights);
}

LightSampler::LightSampler(std::span<const int> light_indices, std::span<const float> weights) {
  if (light_indices.size() != weights.size())
    throw std::invalid_argument("LightSampler: one weight per light index is needed");
  double total = 0;
  int max_index = -1;
  for (size_t k = 0; k < weights.size(); ++k) {
    if (!(weights[k] >= 0.f) || !std::isfinite(weights[k]) || light_indices[k] < 0)
      throw std::invalid_argument("LightSampler: weights must be finite and >= 0, indices >= 0");
    total += weights[k];
    max_index = std::max(max_index, light_indices[k]);
  }
  if (!(total > 0)) return;  // nothing emits: an empty sampler, not a uniform fallback
  // Only lights that can be chosen are candidates: a scene whose NEE reaches one light
  // (the sun beside an environment left to phase sampling, a lone lamp) then needs no
  // search at each scattering event.
  std::vector<float> candidate_weights;
  for (size_t k = 0; k < weights.size(); ++k) {
    if (weights[k] == 0.f) continue;
    indices_.push_back(light_indices[k]);
    candidate_weights.push_back(weights[k]);
  }
  distribution_ = Distribution1D(candidate_weights);
  pmf_by_light_.assign(max_index + 1, 0.f);
  for (size_t k = 0; k < indices_.size(); ++k) pmf_by_light_[indices_[k]] += distribution_.pmf(int(k));
}

LightSampler LightSampler::uniform(int light_count) {
  return LightSampler(std::vector<float>(std::max(light_count, 0), 1.f));
}

LightSampler LightSampler::power(std::span<const Light> lights, const GeometryScene& scene, float lambda_min_nm,
                                 float lambda_max_nm) {
  std::vector<float> weights(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) weights[i] = phi_power(lights[i], scene, lambda_min_nm, lambda_max_nm);
  return LightSampler(weights);
}

std::optional<SampledLight> LightSampler::sample(float u) const {
  if (indices_.empty()) return std::nullopt;
  const int k = indices_.size() == 1 ? 0 : distribution_.sample(u);
  return SampledLight{indices_[k], pmf_by_light_[indices_[k]]};
}

float LightSampler::pmf(int light_index) const {
  return light_index >= 0 && light_index < int(pmf_by_light_.size()) ? pmf_by_light_[light_index] : 0.f;
}

}  // namespace chlorovdb
