// Compositing layers (film/film.h, integrator/aov.h): first-hit depth, normal,
// alpha and albedo against scenes whose values are known exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "integrator/render.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

constexpr AovMask kAll = kAovAlpha | kAovDepth | kAovNormal | kAovAlbedo;

// An orthographic camera at z = 2 looking down -z over [-1, 1]², `n` x `n` pixels; `shapes` and `extra` JSON.
std::string ortho_scene(int n, const std::string& shapes, const std::string& extra = "") {
  return R"({"render": {"resolution": [)" + std::to_string(n) + ", " + std::to_string(n) + R"(], "spp": 1, "wavelengths": 4},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 2},
  "materials": {"grey": {"type": "diffuse", "albedo": 0.5}, "glass": {"type": "dielectric", "ior": 1.5},
                "boundary": {"type": "interface"}},
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": "D65", "scale": 1}],
  "shapes": )" + shapes + extra + "}";
}

Image render_aovs(const std::string& name, const std::string& json, int spp, uint64_t seed, AovMask mask = kAll) {
  const Scene scene = load_scene(write_scene(name, json));
  Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
  film.enable_aovs(mask);
  RenderOptions o;
  o.spp = spp;
  o.seed = test_seed(seed);
  o.threads = 2;
  render(scene, film, o);
  return film.to_image(spp);
}

const ImageLayer& layer(const Image& img, const char* name) {
  const ImageLayer* l = img.find_layer(name);
  if (!l) throw std::runtime_error(std::string("no layer ") + name);
  return *l;
}

// Mean and standard error of channel c of a layer over all pixels (the pixels are i.i.d. where the scene is uniform).
Estimate over_pixels(const ImageLayer& l, size_t c) {
  Estimate e;
  for (size_t p = 0; p < l.pixels.size() / l.channels.size(); ++p) e.add(l.pixels[p * l.channels.size() + c]);
  return e;
}

const std::string kGreyFloor = R"([{"type": "quad", "corner": [-5, -5, 0], "edge_u": [10, 0, 0], "edge_v": [0, 10, 0], "material": "grey"}])";

}  // namespace

TEST(Aov, DepthAndNormalOfATiltedQuadMatchThePlane) {
  // The plane z = x / 4 + 0.1: seen along -z from z = 2, the depth at (x, y) is 1.9 - x / 4, linear in
  // the pixel position, so the box-filtered mean is its value at the pixel centre; the normal is constant.
  for (const bool flipped : {false, true}) {
    const std::string u = R"([8, 0, 2])", v = R"([0, 8, 0])";
    const std::string quad = R"([{"type": "quad", "corner": [-4, -4, -0.9], "edge_u": )" + (flipped ? v : u) +
                             R"(, "edge_v": )" + (flipped ? u : v) + R"(, "material": "grey"}])";
    const std::string json = ortho_scene(8, quad);
    const Scene scene = load_scene(write_scene("tilted", json));
    const Image img = render_aovs("tilted", json, 16, 1);
    const ImageLayer &depth = layer(img, "depth"), &normal = layer(img, "N"), &alpha = layer(img, "alpha");
    ASSERT_EQ(depth.channels, (std::vector<std::string>{"Z", "coverage"}));
    ASSERT_EQ(normal.channels, (std::vector<std::string>{"X", "Y", "Z"}));
    const Vec3 n = normalize(Vec3(-0.25f, 0.f, 1.f));  // facing the camera, whichever way the quad is wound
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        const size_t p = size_t(y) * 8 + size_t(x);
        const Ray r = scene.camera.generate_ray(Point2{x + 0.5f, y + 0.5f}, Point2{0.5f, 0.5f});
        // 16 samples at uniform positions: σ of their mean depth is (pixel width / 4) / sqrt(12 · 16).
        EXPECT_NEAR(depth.pixels[2 * p], 1.9 - r.o.x / 4, 4 * (0.25 / 4) / std::sqrt(12.0 * 16)) << x << "," << y;
        EXPECT_EQ(depth.pixels[2 * p + 1], 1.f);
        EXPECT_NEAR(normal.pixels[3 * p + 0], n.x, 1e-5);
        EXPECT_NEAR(normal.pixels[3 * p + 1], n.y, 1e-5);
        EXPECT_NEAR(normal.pixels[3 * p + 2], n.z, 1e-5);
        EXPECT_EQ(alpha.pixels[p], 1.f);
      }
  }
}

TEST(Aov, HalfCoveredPixelHasHalfAlphaAndTheSurfacesDepth) {
  // One pixel over [-1, 1]², an opaque quad over x < 0: each sample hits with probability 1/2.
  const std::string quad = R"([{"type": "quad", "corner": [-5, -5, 0], "edge_u": [5, 0, 0], "edge_v": [0, 10, 0], "material": "grey"}])";
  const int spp = 4096;
  const Image img = render_aovs("half", ortho_scene(1, quad), spp, 2);
  const double sigma = std::sqrt(0.25 / spp);
  EXPECT_NEAR(layer(img, "alpha").pixels[0], 0.5, 4 * sigma);
  EXPECT_NEAR(layer(img, "depth").pixels[1], 0.5, 4 * sigma);  // coverage
  EXPECT_NEAR(layer(img, "depth").pixels[0], 2.0, 1e-5);        // Z: a mean over the samples that hit
  EXPECT_NEAR(layer(img, "N").pixels[2], 0.5, 4 * sigma);       // the normal, weighted by coverage
  // Nothing at all: alpha 0, Z infinite, coverage 0, normal and albedo 0.
  const Image empty = render_aovs("none", ortho_scene(1, "[]"), 4, 3);
  EXPECT_EQ(layer(empty, "alpha").pixels[0], 0.f);
  EXPECT_TRUE(std::isinf(layer(empty, "depth").pixels[0]));
  EXPECT_EQ(layer(empty, "depth").pixels[1], 0.f);
  for (float v : layer(empty, "N").pixels) EXPECT_EQ(v, 0.f);
  for (float v : layer(empty, "albedo").pixels) EXPECT_EQ(v, 0.f);
}

TEST(Aov, AbsorbingSlabGivesAlphaOneMinusItsTransmittance) {
  // A grey absorber (flat ε over every visible wavelength) in an index-matched box 1 cm thick, nothing
  // behind it: alpha = 1 - exp(-τ), τ = 100 ln10 ε c D. The box is an interface, not a surface.
  const double epsilon = 20000, c_uM = 20, D = 0.01;
  const double tau = 100 * std::log(10.0) * epsilon * c_uM * 1e-6 * D;
  const std::string extra = R"(, "pigments": {"grey": {"extinction": {"table": {"lambda": [300, 900], "value": [20000, 20000]}}}},
  "media": {"ink": {"solvent": "none", "pigments": [{"pigment": "grey", "concentration": 20, "unit": "uM"}]}})";
  const std::string box = R"([{"type": "box", "min": [-5, -5, 0], "max": [5, 5, 0.01], "material": "boundary", "inside": "ink"}])";
  const Image img = render_aovs("slab", ortho_scene(8, box, extra), 16, 4);
  const Estimate a = over_pixels(layer(img, "alpha"), 0);
  EXPECT_NEAR(a.mean(), 1 - std::exp(-tau), 4 * a.sigma() + 1e-6) << "tau " << tau;
  EXPECT_GT(a.sigma(), 0.0);  // the ȳ-weighted estimate over hero wavelengths is noisy, but unbiased
  EXPECT_LT(a.sigma(), 0.01);
  const Estimate coverage = over_pixels(layer(img, "depth"), 1);
  EXPECT_EQ(coverage.mean(), 0.0) << "a medium's boundary is not a surface";
}

TEST(Aov, InterfaceBoxIsTransparentToEveryLayer) {
  // The grey floor at z = 0 seen through an index-matched box holding a clear medium: every layer equals the floor alone.
  const std::string extra = R"(, "media": {"clear": {"solvent": "none"}})";
  const std::string box = R"({"type": "box", "min": [-3, -3, 0.5], "max": [3, 3, 1.5], "material": "boundary", "inside": "clear"})";
  const std::string floor = kGreyFloor.substr(1, kGreyFloor.size() - 2);
  const Image alone = render_aovs("floor", ortho_scene(4, "[" + floor + "]", extra), 8, 5);
  const Image boxed = render_aovs("boxed", ortho_scene(4, "[" + box + ", " + floor + "]", extra), 8, 5);
  for (const char* name : {"alpha", "depth", "N", "albedo"}) {
    const ImageLayer &a = layer(alone, name), &b = layer(boxed, name);
    for (size_t i = 0; i < a.pixels.size(); ++i) EXPECT_EQ(a.pixels[i], b.pixels[i]) << name << " " << i;
  }
  for (size_t p = 0; p < 16; ++p) EXPECT_NEAR(layer(boxed, "depth").pixels[2 * p], 2.0, 1e-5);
}

TEST(Aov, AlbedoOfADiffuseSurfaceSeenThroughGlassIsItsAlbedo) {
  // A glass plate (n = 1.5) between the camera and the grey floor, at normal incidence: the albedo follows the
  // refraction to the floor, so it is the floor's exactly (same wavelengths, same samples); alpha, depth and
  // normal are the plate's top face.
  const std::string plate = R"({"type": "box", "min": [-3, -3, 0.5], "max": [3, 3, 0.6], "material": "glass"})";
  const std::string floor = kGreyFloor.substr(1, kGreyFloor.size() - 2);
  const Image alone = render_aovs("floor_only", ortho_scene(8, "[" + floor + "]"), 8, 6);
  const Image glass = render_aovs("glass_plate", ortho_scene(8, "[" + plate + ", " + floor + "]"), 8, 6);
  const ImageLayer &a = layer(alone, "albedo"), &g = layer(glass, "albedo");
  ASSERT_EQ(g.channels, (std::vector<std::string>{"R", "G", "B"}));
  for (size_t i = 0; i < a.pixels.size(); ++i) EXPECT_EQ(a.pixels[i], g.pixels[i]) << i;
  // And that is the grey's 0.5 in every channel: reflectance under D65, white = 1.
  for (size_t c = 0; c < 3; ++c) {
    const Estimate e = over_pixels(g, c);
    EXPECT_NEAR(e.mean(), 0.5, 4 * e.sigma() + 1e-4) << "channel " << c;
  }
  for (size_t p = 0; p < 64; ++p) {
    EXPECT_EQ(layer(glass, "alpha").pixels[p], 1.f);
    EXPECT_NEAR(layer(glass, "depth").pixels[2 * p], 1.4, 1e-5);
    EXPECT_NEAR(layer(glass, "N").pixels[3 * p + 2], 1.0, 1e-6);
  }
}

TEST(Aov, BeautyIsTheSameWithOrWithoutAovs) {
  const std::string json = ortho_scene(4, kGreyFloor);
  const Image with = render_aovs("beauty_aov", json, 4, 7), without = render_aovs("beauty_plain", json, 4, 7, 0);
  EXPECT_EQ(without.find_layer("alpha"), nullptr);
  EXPECT_EQ(without.layers.size() + 4, with.layers.size());
  for (size_t l = 0; l < without.layers.size(); ++l) EXPECT_EQ(without.layers[l].pixels, with.layers[l].pixels) << without.layers[l].name;
}
