// The excitation continuation's wavelength λ'' (integrator/fluorescence_event.h):
// the reabsorption tables the loader builds, and a mixture whose samples follow
// the density it reports.
#include <gtest/gtest.h>

#include "integrator/fluorescence_event.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// Chlorophyll a (absorbs its own red emission) and a UV dye whose emission lies
// where neither pigment absorbs, in one solution under a UVB lamp.
Scene two_pigment_scene() {
  return load_scene(write_scene("continuation_wavelength", R"({
  "render": {"resolution": [4, 4], "spp": 1, "fluorescence": "full"},
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30},
  "pigments": {
    "chlorophyll_a": {"extinction": "chlorophyll_a", "quantum_yield": 0.23, "emission": "mirror"},
    "uv_dye": {"extinction": {"table": {"lambda": [279.999, 280, 330, 330.001], "value": [0, 20000, 20000, 0]}},
               "quantum_yield": 0.5, "emission": {"gaussian": [760, 8]}}
  },
  "media": {"solution": {"solvent": {"rayleigh": false},
                         "pigments": [{"pigment": "chlorophyll_a", "concentration": 5, "unit": "uM"},
                                      {"pigment": "uv_dye", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
    {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "inside": "solution"},
    {"type": "quad", "corner": [-3, -1, -1], "edge_u": [0, 2, 0], "edge_v": [0, 0, 2],
     "emission": {"spectrum": "UVB", "scale": 10}}
  ]
})"));
}

// The two pigments differ in quantum yield.
const FluorescentPigment& pigment_named(const Scene& scene, const std::string& name) {
  const float q = name == "chlorophyll_a" ? 0.23f : 0.5f;
  for (const auto& pigments : scene.fluorescence)
    for (const FluorescentPigment& fp : pigments)
      if (fp.quantum_yield == q) return fp;
  throw std::runtime_error("no fluorescent pigment " + name);
}

}  // namespace

TEST(ContinuationWavelength, ReabsorptionTablesWhereAnEmissionMeetsAnAbsorption) {
  const Scene scene = two_pigment_scene();
  // Chlorophyll absorbs its own red emission (the Q band overlaps the mirror
  // image) and, with a weight of ~1e-12, the far tail of the dye's Gaussian at
  // 760 nm (its table ends at 700 nm); the dye absorbs neither.
  const FluorescentPigment& chl = pigment_named(scene, "chlorophyll_a");
  ASSERT_EQ(chl.reabsorption.size(), 2u);
  EXPECT_TRUE(pigment_named(scene, "uv_dye").reabsorption.empty());
  EXPECT_GT(chl.reabsorption_choice.pmf(0), 0.999f);
  // Its own table peaks in the red, where the two bands overlap.
  const ExcitationSampler& red = chl.reabsorption[0];
  EXPECT_GT(red.pdf(665.f), 20.f * red.pdf(450.f));
}

TEST(ContinuationWavelength, SamplesFollowTheMixtureDensity) {
  const Scene scene = two_pigment_scene();
  for (const char* name : {"chlorophyll_a", "uv_dye"}) {
    SCOPED_TRACE(name);
    const FluorescentPigment& fp = pigment_named(scene, name);
    // The density integrates to one (midpoint rule on 0.05 nm steps, finer than the 0.5 nm tables).
    constexpr double kStep = 0.05;
    constexpr int kBins = 58;  // 10 nm bins over 250-830 nm
    std::vector<double> bin_mass(kBins, 0.0);
    double total = 0;
    for (double l = kLambdaMinUV + 0.5 * kStep; l < kLambdaMax; l += kStep) {
      const double m = continuation_wavelength_pdf(fp, float(l)) * kStep;
      total += m;
      bin_mass[std::min(kBins - 1, int((l - kLambdaMinUV) / 10.0))] += m;
    }
    EXPECT_NEAR(total, 1.0, 2e-3);
    // Histogram of samples against the bins' mass (4σ binomial), and each
    // sample's pdf is the density at its wavelength.
    constexpr int kSamples = 400000;
    std::vector<int> count(kBins, 0);
    Rng rng(test_seed(23), 0);
    for (int i = 0; i < kSamples; ++i) {
      float pdf;
      const float l = sample_continuation_wavelength(fp, rng, &pdf);
      ASSERT_TRUE(l >= kLambdaMinUV && l < kLambdaMax) << l;
      ASSERT_GT(pdf, 0.f) << l;
      ASSERT_EQ(pdf, continuation_wavelength_pdf(fp, l)) << l;
      ++count[std::min(kBins - 1, int((l - kLambdaMinUV) / 10.f))];
    }
    for (int b = 0; b < kBins; ++b) {
      const double expected = kSamples * bin_mass[b];
      const double sigma = std::sqrt(std::max(1.0, expected * (1.0 - bin_mass[b])));
      EXPECT_NEAR(count[b], expected, 4.0 * sigma) << "bin " << 250 + 10 * b << " nm";
    }
  }
}
