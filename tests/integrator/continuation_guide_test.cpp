// Guided excitation continuations (fluorescence/continuation_guide.h,
// integrator/continuation_guide_training.h): what training learns, and the
// same fluorescence as uniform directions.
#include <gtest/gtest.h>

#include "integrator/continuation_guide_training.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// The default scene's layout, smaller: a glass cuvette of a UVB-only dye on a
// grey floor, a UVB panel to its left whose light reaches the liquid straight
// (the glass connection) and from the floor in front of it (continuations).
std::string cuvette_on_floor(const std::string& directions) {
  return uvb_dye_scene_head(R"("continuation_directions": ")" + directions + R"(")") + R"(
    {"type": "quad", "corner": [-40, 0, -40], "edge_u": [0, 0, 80], "edge_v": [80, 0, 0], "material": "floor"},
    {"type": "box", "min": [-2.2, 0.001, -2.2], "max": [2.2, 6.4, 2.2], "material": "glass"},
    {"type": "box", "min": [-2.0, 0.2, -2.0], "max": [2.0, 6.2, 2.0], "material": "glass_to_solution",
     "inside": "solution"},
    {"type": "quad", "corner": [-14, 1, -4], "edge_u": [0, 8, 0], "edge_v": [0, 0, 8],
     "emission": {"spectrum": "UVB", "scale": 1500}}
  ]
})";
}

// Fluorescence (four red lanes) along a camera ray through the cuvette, low in
// the liquid where the floor's light matters most.
Estimate fluorescence_along_ray(const Scene& scene, int paths, uint64_t seed) {
  return red_fluorescence_along(scene, Ray{{-0.01f, 0.01f, 0.2f}, {0, 0, -1}}, paths, seed);
}

}  // namespace

TEST(ContinuationGuide, TrainingLearnsAGuideOnlyForTheFluorescentMedium) {
  const Scene scene = load_scene(write_scene("guide_cuvette", cuvette_on_floor("guided")));
  ASSERT_TRUE(uses_continuation_guides(scene));
  const std::vector<ContinuationGuide> guides = train_continuation_guides(scene);
  ASSERT_EQ(guides.size(), scene.media.size());
  int guided = 0;
  for (size_t m = 0; m < guides.size(); ++m) {
    EXPECT_EQ(!guides[m].empty(), !scene.fluorescence[m].empty()) << scene.medium_names[m];
    guided += !guides[m].empty();
  }
  EXPECT_EQ(guided, 1);
  // The grid covers the liquid (4 x 6 x 4 cm): 3 x 4 x 3 cells, the longest axis 4.
  const auto& g = guides[size_t(std::find(scene.medium_names.begin(), scene.medium_names.end(), "solution") -
                                scene.medium_names.begin())];
  EXPECT_EQ(g.cell_counts(), (std::array<int, 3>{3, 4, 3}));
  EXPECT_NEAR(g.bounds().lo.y, 0.002f, 2e-4f);
  EXPECT_NEAR(g.bounds().hi.y, 0.062f, 2e-4f);
  // Training is deterministic: the same guide twice.
  const std::vector<ContinuationGuide> again = train_continuation_guides(scene);
  const Vec3 x{-0.01f, 0.01f, 0.f};
  for (int b = 0; b < kDirectionBins; b += 5) {
    const Vec3 w = direction_in_bin(b, Point2{0.5f, 0.5f});
    for (size_t m = 0; m < guides.size(); ++m) ASSERT_EQ(guides[m].pdf(x, w), again[m].pdf(x, w));
  }
}

TEST(ContinuationGuide, TheLearnedGuideLooksTowardTheLampAndTheFloorItLights) {
  // From low in the liquid, the indirect UVB comes from the left: the floor in
  // front of the panel, and the panel through paths with a reflection in the
  // glass. The guided half of the density puts most of its mass there.
  const Scene scene = load_scene(write_scene("guide_cuvette_dir", cuvette_on_floor("guided")));
  GuideTraining training;
  training.seed = test_seed(5);
  const std::vector<ContinuationGuide> guides = train_continuation_guides(scene, training);
  const ContinuationGuide* g = nullptr;
  for (const auto& guide : guides)
    if (!guide.empty()) g = &guide;
  ASSERT_NE(g, nullptr);
  const Vec3 x{-0.01f, 0.01f, 0.f};
  double toward_lamp = 0, total = 0;
  for (int b = 0; b < kDirectionBins; ++b) {
    const Vec3 w = direction_in_bin(b, Point2{0.5f, 0.5f});
    const double p = g->pdf(x, w);
    total += p;
    if (w.x < 0.f) toward_lamp += p;
  }
  const double guided_share = (toward_lamp / total - 0.5 * g->uniform_share()) / (1.0 - g->uniform_share());
  std::printf("guided density toward the lamp's half of the sphere: %.2f\n", guided_share);
  // Uniform directions give 0.5; over training seeds (offsets 0-5) this read 0.60-0.89.
  EXPECT_GT(guided_share, 0.55);
}

TEST(ContinuationGuide, GuidedContinuationsAgreeWithUniformOnes) {
  Scene uniform = load_scene(write_scene("guide_cuvette_uniform", cuvette_on_floor("uniform")));
  Scene guided = load_scene(write_scene("guide_cuvette_guided", cuvette_on_floor("guided")));
  EXPECT_FALSE(uses_continuation_guides(uniform));
  prepare_continuation_guides(guided);
  ASSERT_TRUE(guided.continuation_guides);
  constexpr int kPaths = 40000;
  const Estimate u = fluorescence_along_ray(uniform, kPaths, 11);
  const Estimate g = fluorescence_along_ray(guided, kPaths, 12);
  const double sigma = std::sqrt(u.sigma() * u.sigma() + g.sigma() * g.sigma());
  std::printf("fluorescence: uniform %.5g +- %.2g, guided %.5g +- %.2g\n", u.mean(), u.sigma(), g.mean(), g.sigma());
  EXPECT_NEAR(g.mean(), u.mean(), 4 * sigma);
  EXPECT_GT(u.mean(), 0.0);
  // The guide is trained once per scene and reused.
  const auto trained = guided.continuation_guides;
  EXPECT_EQ(prepare_continuation_guides(guided), 0.0);
  EXPECT_EQ(guided.continuation_guides, trained);
}
