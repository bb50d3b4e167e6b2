// Camera wavelengths (render.camera_wavelengths, spectra/wavelength_sampling.h):
// the scene's mixture and the eye's density give the same image, and a lamp's
// mercury lines cost the mixture a fraction of the eye's noise.
#include <gtest/gtest.h>

#include "integrator/render.h"
#include "spectra/color.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// An orthographic camera looking straight at a quad that emits the Philips TL12
// tube's spectrum (mercury lines at 405, 436, 546 and 578 nm in 1 nm bins): every
// pixel sees Le and nothing else, so its only noise is the wavelengths'.
std::string lamp_scene(const std::string& camera_wavelengths) {
  return R"({"render": {"resolution": [32, 32], "spp": 4, "wavelengths": 4, "camera_wavelengths": ")" +
         camera_wavelengths + R"("},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 2},
  "shapes": [{"type": "quad", "corner": [-5, -5, 0], "edge_u": [10, 0, 0], "edge_v": [0, 10, 0],
              "emission": {"spectrum": "UVB-TL12", "scale": 1}}]})";
}

struct Channels {
  Estimate rgb[3];
};

// Per channel of the total layer, mean and standard error over the pixels (i.i.d. here).
Channels render_lamp(const Scene& scene, uint64_t seed) {
  Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
  RenderOptions o;
  o.spp = scene.settings.spp;
  o.seed = test_seed(seed);
  o.threads = 2;
  render(scene, film, o);
  Channels c;
  for (size_t p = 0; p < size_t(scene.settings.width * scene.settings.height); ++p) {
    const RGB v = film.pixel_mean(0, p, o.spp);
    c.rgb[0].add(v.r), c.rgb[1].add(v.g), c.rgb[2].add(v.b);
  }
  return c;
}

}  // namespace

TEST(CameraWavelengths, SceneMixtureIsTheDefaultAndVisibleIsTheEyesDensity) {
  const Scene mixture = load_scene(write_scene("lamp_mixture", lamp_scene("scene")));
  EXPECT_EQ(mixture.settings.camera_wavelengths, CameraWavelengths::scene);
  EXPECT_FALSE(mixture.camera_wavelengths.is_visible());
  // The 436 nm line draws lanes far more often than the eye's density would.
  double line = 0, eye = 0;
  for (float l = 434.25f; l < 438.f; l += 0.5f) {
    line += mixture.camera_wavelengths.pdf(l) * 0.5;
    eye += visible_wavelength_pdf(l) * 0.5;
  }
  EXPECT_GT(line, 10 * eye);
  const Scene visible = load_scene(write_scene("lamp_visible", lamp_scene("visible")));
  EXPECT_TRUE(visible.camera_wavelengths.is_visible());
}

TEST(CameraWavelengths, LampSeenDirectlyMatchesItsColourWithEitherDensity) {
  const Scene mixture = load_scene(write_scene("lamp_mixture", lamp_scene("scene")));
  const Scene visible = load_scene(write_scene("lamp_visible", lamp_scene("visible")));
  const RGB exact = xyz_to_linear_srgb(spectrum_to_xyz(emission_spectrum(mixture.lights.at(0))));
  const Channels m = render_lamp(mixture, 41), v = render_lamp(visible, 43);
  const double expected[3] = {exact.r, exact.g, exact.b};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(m.rgb[c].mean(), expected[c], 4 * m.rgb[c].sigma()) << "mixture, channel " << c;
    EXPECT_NEAR(v.rgb[c].mean(), expected[c], 4 * v.rgb[c].sigma()) << "visible, channel " << c;
    // Measured 0.21, 0.27 and 0.053 of the eye's (R, G, B; seeds 41, 43): the lines
    // no longer set the noise. Half is the claim.
    EXPECT_LT(m.rgb[c].sigma(), 0.5 * v.rgb[c].sigma()) << "channel " << c;
  }
}
