// Excitation through dielectric interfaces (issue 23).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "integrator/transport.h"
#include "materials/dielectric.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

constexpr float kLambdas[4] = {665.f, 675.f, 685.f, 700.f};

std::string cuvette_json(const std::string& mode, const std::string& glass, const std::string& inner,
                         const std::string& pigment) {
  return R"({
  "length_unit": "cm",
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": ")" + mode +
         R"(", "excitation_through_glass": "block", "max_depth": 64},
  "camera": {"type": "orthographic", "position": [0, 3, 20], "look_at": [0, 3, 0], "height": 6},
  "pigments": {"chl": )" + pigment + R"(},
  "materials": {"glass": )" + glass + R"(, "glass_to_solution": )" + inner + R"(},
  "media": {"solution": {"solvent": {"rayleigh": false},
                         "pigments": [{"pigment": "chl", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
    {"type": "box", "min": [-2.2, 0, -2.2], "max": [2.2, 6.4, 2.2], "material": "glass"},
    {"type": "box", "min": [-2.0, 0.2, -2.0], "max": [2.0, 6.2, 2.0], "material": "glass_to_solution", "inside": "solution"},
    {"type": "quad", "corner": [60, -17, 20], "edge_u": [0, 40, 0], "edge_v": [0, 0, -40],
     "emission": {"spectrum": "UVB-TL12", "scale": 22500}}
  ]
})";
}

struct Sample { double v; uint64_t i; };

Estimate run(const Scene& scene, int paths, uint64_t seed, std::vector<Sample>* top) {
  Estimate e;
  PathStats stats;
  const float pdf[4] = {1, 1, 1, 1};
  for (int i = 0; i < paths; ++i) {
    Rng rng(test_seed(seed), uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(kLambdas, pdf, 4);
    const PathRadiance L = trace_path(scene, Ray{{0, 0.03f, 0.2f}, {0, 0, -1}}, scene.camera_medium, lambda, rng, stats);
    const double v = L.fluorescence.average(4);
    e.add(v);
    if (top) top->push_back({v, uint64_t(i)});
  }
  if (top) {
    std::partial_sort(top->begin(), top->begin() + 10, top->end(), [](auto a, auto b) { return a.v > b.v; });
    top->resize(10);
  }
  return e;
}

}  // namespace

// Fresnel transmission of a face at incidence angle theta_i (radians) from index n_i into n_t.
double face_transmission(double theta_i, double n_i, double n_t) {
  return 1.0 - fresnel_dielectric(float(std::cos(theta_i)), float(n_t / n_i));
}

TEST(StraightThroughFresnel, GlassPlateInAirAtObliqueIncidenceDoesNotReflectTotally) {
  // A plate in air, light 60° off its normal: past the glass-air critical angle
  // (41.8°) if the unrefracted angle is tested from inside the glass, but light
  // arriving from air never reflects totally. Exact: T_air→glass(60°) ·
  // T_glass→air(θ_g), beam compression cancelling between parallel faces.
  const float theta = 60.f * float(M_PI) / 180.f;
  const Vec3 wi{std::sin(theta), 0.f, std::cos(theta)};  // from the medium point toward the light, above
  const Vec3 ng[2] = {{0, 0, -1}, {0, 0, 1}};  // the plate's lower face (outward: down), then its upper face
  const float ior[2] = {1.5f, 1.5f};
  const double theta_g = std::asin(std::sin(theta) / 1.5);
  const double exact = face_transmission(theta, 1.0, 1.5) * face_transmission(theta_g, 1.5, 1.0);
  EXPECT_NEAR(straight_through_transmission(ng, ior, 2, wi), exact, 1e-5);
  EXPECT_GT(exact, 0.8);
}

TEST(StraightThroughFresnel, WaterGlassAirStackUsesTheRefractedAnglesAndBeamCompression) {
  // Water (1.337) under a glass wall (1.5) under air, light 70° off the normal:
  // the angles are those of the light refracted into glass and then into water,
  // and a collimated beam's irradiance changes by cos θ_air / cos θ_water.
  const float theta = 70.f * float(M_PI) / 180.f;
  const Vec3 wi{0.f, std::sin(theta), std::cos(theta)};
  // The water-glass face (a box of water: outward normal up, relative IOR water/glass),
  // then the glass-air face (the glass box's top, outward up).
  const Vec3 ng[2] = {{0, 0, 1}, {0, 0, 1}};
  const float ior[2] = {1.337f / 1.5f, 1.5f};
  const double theta_g = std::asin(std::sin(theta) / 1.5), theta_w = std::asin(std::sin(theta) / 1.337);
  const double exact = face_transmission(theta, 1.0, 1.5) * face_transmission(theta_g, 1.5, 1.337) *
                       std::cos(theta) / std::cos(theta_w);
  EXPECT_NEAR(straight_through_transmission(ng, ior, 2, wi), exact, 1e-5);
  // Seen from the water at 70°, light leaving to air would reflect totally: the
  // old per-face test at the unrefracted angle returned 0 here.
  EXPECT_GT(exact, 0.2);
  // From the other side (the light in water, the point in air) past the critical angle: total reflection.
  const Vec3 ng_rev[2] = {{0, 0, -1}, {0, 0, -1}};
  const float ior_rev[2] = {1.5f, 1.337f / 1.5f};
  const Vec3 down{0.f, std::sin(theta), -std::cos(theta)};
  EXPECT_EQ(straight_through_transmission(ng_rev, ior_rev, 2, down), 0.f);
}

TEST(StraightThroughFresnel, NormalIncidenceIsTheProductOfFaceTransmissions) {
  const Vec3 ng[2] = {{0, 0, 1}, {0, 0, 1}};
  const float ior[2] = {1.337f / 1.5f, 1.5f};
  const double r1 = std::pow(0.5 / 2.5, 2), r2 = std::pow(0.163 / 2.837, 2);
  EXPECT_NEAR(straight_through_transmission(ng, ior, 2, Vec3{0, 0, 1}), (1 - r1) * (1 - r2), 1e-5);
}
