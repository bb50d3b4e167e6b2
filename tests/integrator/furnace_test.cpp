// Furnace tests: in a uniform environment of radiance 1, a non-absorbing object
// (albedo-1 diffuse sphere, or a pure scatterer) is invisible: every path
// estimates exactly radiance 1 in expectation, at every wavelength.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include "grids/vdb_file.h"
#include "integrator/render.h"
#include "spectra/color.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// Camera rays through pixel (4, 4), or over the whole 8×8 film.
void expect_furnace(const Scene& scene, int paths, bool whole_film = false) {
  std::array<Estimate, 8> e;
  PathStats stats;
  for (int i = 0; i < paths; ++i) {
    Rng rng = sample_rng(11, i % 7, i / 7, i);
    SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 8);
    const Point2 film = whole_film ? Point2{8.f * rng.uniform(), 8.f * rng.uniform()}
                                   : Point2{4.f + rng.uniform(), 4.f + rng.uniform()};
    const Ray ray = scene.camera.generate_ray(film, {0.5f, 0.5f});
    const PathRadiance L = trace_path(scene, ray, scene.camera_medium, lambda, rng, stats);
    for (int k = 0; k < 8; ++k) e[k].add(L.other[k] + L.fluorescence[k]);
  }
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(e[k].mean(), 1.0, 4 * e[k].sigma() + 1e-4) << "lane " << k;
}

}  // namespace

TEST(Furnace, WhiteDiffuseSphere) {
  const Scene scene = load_scene(write_scene("furnace_sphere", R"({
    "render": {"resolution": [8, 8], "max_depth": 1000, "wavelengths": 8},
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 10},
    "materials": {"white": {"type": "diffuse", "albedo": 1}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })"));
  expect_furnace(scene, 20000);
}

// A lossless dielectric is invisible too, also on a coarse smooth-shaded mesh,
// where grazing rays often meet faces whose interpolated normal disagrees with
// the face about their side: the dielectric is then sampled in the face's frame
// and its path weight must still be Fresnel's. The sphere fills the film, so
// rays reach its silhouette, and inside it light is guided by grazing bounces.
TEST(Furnace, CoarseSmoothShadedGlassMesh) {
  const Scene scene = load_scene(write_scene("furnace_glass", R"({
    "render": {"resolution": [8, 8], "max_depth": 1000, "wavelengths": 8},
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 28},
    "materials": {"glass": {"type": "dielectric", "ior": 1.5}},
    "shapes": [{"type": "mesh", "file": ")" + write_smooth_sphere("furnace_glass_ball", 1.f, 6, 12) +
                                                       R"(", "material": "glass"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })"));
  expect_furnace(scene, 20000, true);
}

TEST(Furnace, PureScatteringMediumWithMolecularAndParticlePhase) {
  const Scene scene = load_scene(write_scene("furnace_medium", R"({
    "render": {"resolution": [8, 8], "max_depth": 100000, "wavelengths": 8},
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 10},
    "materials": {"boundary": {"type": "interface"}},
    "media": {"cloud": {"solvent": {"absorption": 0, "rayleigh": true},
                        "scattering": {"coefficient": 3, "g": 0.6}}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "boundary", "inside": "cloud"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })"));
  expect_furnace(scene, 20000);
}

TEST(Determinism, SameImageForAnyThreadCount) {
  const Scene scene = load_scene(write_scene("determinism", R"({
    "render": {"resolution": [24, 20], "wavelengths": 4},
    "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "fov": 40},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.6}, "glass": {"type": "dielectric", "ior": 1.5}},
    "shapes": [{"type": "quad", "corner": [-3, -1, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0], "material": "floor"},
               {"type": "sphere", "center": [0, 0, 0], "radius": 0.8, "material": "glass"},
               {"type": "quad", "corner": [-0.5, 2, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
                "emission": {"spectrum": "F2", "scale": 0.1}}],
    "lights": [{"type": "point", "position": [2, 2, 2], "spectrum": "D65", "scale": 0.05}]
  })"));
  auto run = [&](int threads) {
    Film film(24, 20, film_layer_names(), ColorSpace::sRGB);
    RenderOptions o;
    o.spp = 6;
    o.threads = threads;
    o.seed = test_seed(42);
    chlorovdb::render(scene, film, o);
    return film.raw_xyz(0);
  };
  const auto one = run(1), two = run(2);
  ASSERT_EQ(one.size(), two.size());
  double total = 0;
  for (size_t i = 0; i < one.size(); ++i) {
    ASSERT_EQ(one[i], two[i]) << "value " << i;
    total += one[i];
  }
  EXPECT_GT(total, 0.0);
}

TEST(Render, StopFlagKeepsOnlyCompletePasses) {
  const Scene scene = load_scene(write_scene("interrupt", R"({
    "render": {"resolution": [16, 16], "wavelengths": 4},
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]},
    "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })"));
  Film film(16, 16, film_layer_names(), ColorSpace::sRGB);
  std::atomic<bool> stop{false};
  RenderOptions o;
  o.spp = 64;
  o.stop = &stop;
  o.on_pass = [&](int done) {
    if (done >= 2) stop = true;
  };
  const RenderStats stats = chlorovdb::render(scene, film, o);
  EXPECT_TRUE(stats.interrupted);
  EXPECT_EQ(stats.samples_done, 2);  // passes of 1 and 1 sample
}

TEST(Skips, AbsorbingOnlyMediumByTransmittanceMatchesDeltaTracking) {
  // A 2 cm chlorophyll solution in front of a uniform environment: tracking the
  // camera path by transmittance (the skip) and by delta tracking agree, and
  // the skip has lower variance because no lane is lost to a hero absorption.
  auto scene_json = [](bool skip) {
    return std::string(R"({
      "render": {"resolution": [8, 8], "wavelengths": 8, "skip_unneeded_work": )") +
           (skip ? "true" : "false") + R"(},
      "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 5},
      "pigments": {"chl": {"extinction": "chlorophyll_a"}},
      "materials": {"boundary": {"type": "interface"}},
      "media": {"solution": {"solvent": {"rayleigh": false},
                             "pigments": [{"pigment": "chl", "concentration": 30, "unit": "uM"}]}},
      "shapes": [{"type": "box", "min": [-1, -1, -0.01], "max": [1, 1, 0.01], "material": "boundary",
                  "inside": "solution"}],
      "lights": [{"type": "environment", "spectrum": "D65", "scale": 0.01}]
    })";
  };
  const Scene skip = load_scene(write_scene("skip_on", scene_json(true)));
  const Scene track = load_scene(write_scene("skip_off", scene_json(false)));
  ASSERT_TRUE(skip.track_by_transmittance(0));
  ASSERT_FALSE(track.track_by_transmittance(0));
  // Hero-wavelength spectral MIS is unbiased over random wavelength sets (what
  // the film integrates), not lane by lane for fixed wavelengths: compare XYZ.
  std::array<Estimate, 3> a, b;
  PathStats stats;
  for (int i = 0; i < 40000; ++i) {
    for (const Scene* s : {&skip, &track}) {
      Rng rng = sample_rng(3, 0, 0, i);
      SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 8);
      const PathRadiance L = trace_path(*s, Ray{{0, 0, 4}, {0, 0, -1}}, -1, lambda, rng, stats);
      const XYZ xyz = to_xyz(L.other, lambda);
      auto& e = s == &skip ? a : b;
      e[0].add(xyz.x), e[1].add(xyz.y), e[2].add(xyz.z);
    }
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a[k].mean(), b[k].mean(), 4 * std::hypot(a[k].sigma(), b[k].sigma())) << "XYZ component " << k;
    EXPECT_LE(a[k].sigma(), b[k].sigma()) << "XYZ component " << k;
  }
}

TEST(Furnace, HeterogeneousGridScattererWithNullCollisions) {
  // A pure scatterer whose density varies (so sigma_t < sigma_maj and null
  // collisions happen) must vanish in the furnace too: null collisions weight
  // the MIS ratios r_u and r_l by the same sampled pdf.
  DenseGrid g({16, 16, 16}, 0.f);
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) g.at(x, y, z) = float((x * 7 + y * 13 + z * 5) % 16) / 15.f;
  g.world_from_index = Transform::translate(Vec3(-1.f + 1.f / 16)) * Transform::scale(Vec3(2.f / 16));
  g.metadata.name = "density";
  const auto vdb = scratch_dir("integrator_tests") / "furnace_grid.vdb";
  write_concentration_grid(vdb, g);
  const Scene scene = load_scene(write_scene("furnace_grid", R"({
    "render": {"resolution": [8, 8], "max_depth": 100000, "wavelengths": 8},
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 10},
    "media": {"cloud": {"solvent": "none", "scattering": {"coefficient": {"file": ")" + vdb.string() + R"(",
                        "name": "density", "scale": 4}, "g": 0.3}}},
    "lights": [{"type": "environment", "spectrum": 1}]
  })"));
  expect_furnace(scene, 20000);
}
