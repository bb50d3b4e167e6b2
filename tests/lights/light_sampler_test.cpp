#include <gtest/gtest.h>

#include <vector>

#include "core/rng.h"
#include "lights/light_sampler.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Chi-square of sampled frequencies against pmf over `n` light indices.
double chi_square(const LightSampler& sampler, int n, int count, uint64_t seed) {
  std::vector<int> hist(n, 0);
  Rng rng(test_seed(seed), 0);
  for (int i = 0; i < count; ++i) {
    const auto s = sampler.sample(rng.uniform());
    EXPECT_TRUE(s);
    EXPECT_EQ(s->pmf, sampler.pmf(s->index));
    ++hist[s->index];
  }
  double chi2 = 0;
  for (int i = 0; i < n; ++i) {
    const double e = count * sampler.pmf(i);
    if (e == 0) {
      EXPECT_EQ(hist[i], 0) << "light " << i << " has pmf 0 but was chosen";
      continue;
    }
    chi2 += (hist[i] - e) * (hist[i] - e) / e;
  }
  return chi2;
}

}  // namespace

TEST(LightSampler, FrequenciesMatchPmf) {
  const std::vector<float> weights{1.f, 4.f, 0.f, 2.5f, 0.5f};
  const LightSampler sampler(weights);
  EXPECT_FLOAT_EQ(sampler.pmf(1), 0.5f);
  EXPECT_EQ(sampler.pmf(2), 0.f);
  EXPECT_EQ(sampler.pmf(17), 0.f);
  EXPECT_LT(chi_square(sampler, 5, 200000, 1), 16.3) << "3 dof, p = 0.001";
}

TEST(LightSampler, SubsetOnlyChoosesItsMembers) {
  const std::vector<int> indices{6, 2, 9};
  const std::vector<float> weights{3.f, 1.f, 1.f};
  const LightSampler sampler(indices, weights);
  EXPECT_FLOAT_EQ(sampler.pmf(6), 0.6f);
  EXPECT_FLOAT_EQ(sampler.pmf(2), 0.2f);
  EXPECT_EQ(sampler.pmf(0), 0.f);
  EXPECT_EQ(sampler.pmf(7), 0.f);
  EXPECT_LT(chi_square(sampler, 10, 100000, 2), 13.8) << "2 dof, p = 0.001";
}

TEST(LightSampler, ZeroWeightLightsAreNeverCandidates) {
  // The cloud benchmark's camera paths: an environment (weight 0, left to phase
  // sampling) and the sun. The sun is chosen for every u, with pmf 1.
  const LightSampler sampler(std::vector<float>{0.f, 2.f, 0.f});
  EXPECT_EQ(sampler.pmf(0), 0.f);
  EXPECT_EQ(sampler.pmf(1), 1.f);
  for (const float u : {0.f, 0.25f, 0.5f, 0x1.fffffep-1f}) {
    const auto s = sampler.sample(u);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->index, 1);
    EXPECT_EQ(s->pmf, 1.f);
  }
  // With zero weights between positive ones, the frequencies still follow the pmf.
  const LightSampler mixed(std::vector<int>{4, 1, 7, 3}, std::vector<float>{0.f, 1.f, 0.f, 3.f});
  EXPECT_FLOAT_EQ(mixed.pmf(3), 0.75f);
  EXPECT_EQ(mixed.pmf(4), 0.f);
  EXPECT_LT(chi_square(mixed, 8, 100000, 4), 10.8) << "1 dof, p = 0.001";
}

TEST(LightSampler, UniformAndEmpty) {
  const LightSampler uniform = LightSampler::uniform(4);
  for (int i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(uniform.pmf(i), 0.25f);
  EXPECT_LT(chi_square(uniform, 4, 100000, 3), 16.3);
  EXPECT_FALSE(LightSampler().sample(0.5f));
  EXPECT_TRUE(LightSampler(std::vector<float>{0.f, 0.f}).empty());
  EXPECT_THROW(LightSampler(std::vector<float>{1.f, -1.f}), std::invalid_argument);
}

TEST(LightSampler, PowerWeightsAndExcitationBand) {
  GeometryScene scene;
  scene.commit();
  std::vector<Light> lights{
      PointLight{{0, 0, 0}, Spectrum::constant(1.f), 1.f},
      PointLight{{0, 0, 0}, Spectrum::constant(1.f), 3.f},
      // Emits only around 300 nm (UVB): no power in a visible band.
      PointLight{{0, 0, 0}, Spectrum::tabulated({290.f, 300.f, 310.f}, {0.f, 10.f, 0.f}), 1.f},
  };
  for (Light& l : lights) preprocess(l, {});
  const LightSampler all = LightSampler::power(lights, scene);
  const float p0 = phi_power(lights[0], scene), p1 = phi_power(lights[1], scene), p2 = phi_power(lights[2], scene);
  EXPECT_NEAR(all.pmf(1) / all.pmf(0), 3.f, 1e-5f);
  EXPECT_NEAR(all.pmf(2), p2 / (p0 + p1 + p2), 1e-6f);
  const LightSampler visible = LightSampler::power(lights, scene, 400.f, 700.f);
  EXPECT_EQ(visible.pmf(2), 0.f);
  EXPECT_FLOAT_EQ(visible.pmf(1), 0.75f);
  const LightSampler uvb = LightSampler::power(lights, scene, 295.f, 305.f);  // 75 vs 3 x 10
  EXPECT_GT(uvb.pmf(2), uvb.pmf(1));
}
