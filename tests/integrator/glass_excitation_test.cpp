// Excitation through dielectric interfaces (issue 23).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "integrator/transport.h"
#include "materials/dielectric.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// Fresnel transmission of a face at incidence angle theta_i (radians) from index n_i into n_t.
double face_transmission(double theta_i, double n_i, double n_t) {
  return 1.0 - fresnel_dielectric(float(std::cos(theta_i)), float(n_t / n_i));
}

}  // namespace

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

namespace {

// A 4 cm cuvette (tools/experiments/glass_excitation.sh) with glass of a chosen
// IOR, lit from the side by a 40 cm UVB panel at 60 cm; `pigment` is a JSON object.
std::string cuvette_json(const std::string& mode, const std::string& glass, const std::string& inner,
                         const std::string& pigment) {
  return R"({
  "length_unit": "cm",
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": ")" + mode +
         R"(", "excitation_through_glass": "block", "max_depth": 64},
  "camera": {"type": "orthographic", "position": [0, 3, 20], "look_at": [0, 3, 0], "height": 6},
  "pigments": {"dye": )" + pigment + R"(},
  "materials": {"glass": )" + glass + R"(, "glass_to_solution": )" + inner + R"(},
  "media": {"solution": {"solvent": {"rayleigh": false},
                         "pigments": [{"pigment": "dye", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
    {"type": "box", "min": [-2.2, 0, -2.2], "max": [2.2, 6.4, 2.2], "material": "glass"},
    {"type": "box", "min": [-2.0, 0.2, -2.0], "max": [2.0, 6.2, 2.0], "material": "glass_to_solution",
     "inside": "solution"},
    {"type": "quad", "corner": [60, -17, 20], "edge_u": [0, 40, 0], "edge_v": [0, 0, -40],
     "emission": {"spectrum": "UVB-TL12", "scale": 22500}}
  ]
})";
}

// Mean fluorescence (over four red lanes) along the camera ray through the cuvette's centre.
Estimate cuvette_fluorescence(const Scene& scene, int paths, uint64_t seed) {
  return red_fluorescence_along(scene, Ray{{0, 0.03f, 0.2f}, {0, 0, -1}}, paths, seed);
}

// A dye that absorbs only in the UVB (280–330 nm) and emits in the red: it never
// reabsorbs its own light, so with nothing that reflects, `direct` is exact.
const char* kUvbDye = R"({"extinction": {"table": {"lambda": [279.999, 280, 330, 330.001],
  "value": [0, 20000, 20000, 0]}}, "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}})";

}  // namespace

TEST(GlassExcitation, FullThroughIndexMatchedGlassAgreesWithDirect) {
  // Glass of IOR 1 (a dielectric that neither reflects nor bends) is the same
  // scene as no glass. `direct` crosses it straight (exact: R = 0); `full` with
  // "block" stops the excitation rays at it, so all its excitation arrives by
  // continuation paths refracted through both walls to the panel. They agree:
  // the continuation neither double-counts the panel nor drops it.
  const std::string g1 = R"({"type": "dielectric", "ior": 1})";
  const std::string none = R"({"type": "interface"})";
  const Scene direct = load_scene(write_scene("cuvette_direct", cuvette_json("direct", none, none, kUvbDye)));
  const Scene full = load_scene(write_scene("cuvette_full_ior1", cuvette_json("full", g1, g1, kUvbDye)));
  const Estimate a = cuvette_fluorescence(direct, 20000, 31);
  const Estimate b = cuvette_fluorescence(full, 800000, 32);
  ASSERT_GT(a.mean(), 20 * a.sigma());
  std::printf("full through IOR-1 glass / direct: %.4f (sigma %.4f)\n", b.mean() / a.mean(),
              std::hypot(a.sigma(), b.sigma()) / a.mean());
  EXPECT_NEAR(b.mean(), a.mean(), 4 * std::hypot(a.sigma(), b.sigma()))
      << "full/direct " << b.mean() / a.mean() << " (σ/mean " << b.sigma() / b.mean() << ")";
}
