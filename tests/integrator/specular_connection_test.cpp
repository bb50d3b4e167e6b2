// Excitation connections through parallel planar glass (integrator/specular_connection.h):
// the planar solve against Fermat's principle, the generalised geometry term
// against finite differences, and fluence through a glass wall against closed
// forms (collimated and point light) and an independent forward-refraction estimate.
#include "integrator/specular_connection.h"

#include <cmath>
#include <cstdio>
#include <functional>

#include "core/sampling.h"
#include "integrator/excitation_connection.h"
#include "integrator/fluorescence_event.h"
#include "materials/bsdf.h"
#include "test_scenes.h"
#include "test_seed.h"

namespace chlorovdb::test {
namespace {

// Solution (relative index 1) | glass (1/0.8913) | air (that / 1.5).
constexpr double kEtaSolutionGlass = 0.8913, kEtaGlass = 1.5;
const std::array<double, 3> kN{1.0, 1.0 / kEtaSolutionGlass, 1.0 / kEtaSolutionGlass / kEtaGlass};

double golden_min(const std::function<double(double)>& f, double a, double b) {
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  for (int i = 0; i < 200; ++i) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (f(c) < f(d)) b = d;
    else a = c;
  }
  return 0.5 * (a + b);
}

TEST(SpecularConnection, PlanarSolveMatchesFermat) {
  // Two interfaces: minimise the optical path length over both vertices
  // (nested golden sections; the OPL is convex) and compare the vertices.
  const std::array<std::array<double, 3>, 3> heights{{{0.02, 0.002, 0.278}, {0.001, 0.004, 0.05}, {0.03, 0.01, 1e-3}}};
  // Past the end of a layer's reach (the air layer only 1 mm thick, everything
  // else denser) a lateral offset has no solution.
  EXPECT_FALSE(solve_planar_invariant(std::array<double, 3>{0.03, 0.01, 0.0}, kN, 0.6));
  for (const auto& h : heights)
    for (double R : {0.0, 1e-4, 0.01, 0.1, 0.6}) {
      const auto s = solve_planar_invariant(h, kN, R);
      ASSERT_TRUE(s);
      EXPECT_NEAR(planar_lateral_offset(h, kN, *s), R, 1e-7 * (1 + R));
      auto opl = [&](double u1, double u2) {
        return kN[0] * std::hypot(h[0], u1) + kN[1] * std::hypot(h[1], u2 - u1) + kN[2] * std::hypot(h[2], R - u2);
      };
      auto best_u2 = [&](double u1) { return golden_min([&](double u2) { return opl(u1, u2); }, -1, 2); };
      const double u1 = golden_min([&](double u1) { return opl(u1, best_u2(u1)); }, -1, 2);
      const double u2 = best_u2(u1);
      const double r1 = h[0] * *s / std::sqrt(kN[0] * kN[0] - *s * *s);
      const double r2 = r1 + h[1] * *s / std::sqrt(kN[1] * kN[1] - *s * *s);
      EXPECT_NEAR(r1, u1, 1e-6) << "R " << R;
      EXPECT_NEAR(r2, u2, 1e-6) << "R " << R;
    }
}

TEST(SpecularConnection, GeometryTermMatchesFiniteDifferences) {
  // dω_0/dA_⊥ = |det[d0, ∂d0/∂u, ∂d0/∂v]| with u, v spanning the plane
  // perpendicular to the last leg at the end point.
  const std::array<double, 3> h{0.02, 0.002, 0.278};
  const double H = h[0] + h[1] + h[2];
  // d0 for the end point (a, b, z): lateral (a, b), last layer z - h0 - h1 thick.
  auto d0_of = [&](double a, double b, double z) {
    const std::array<double, 3> hh{h[0], h[1], z - h[0] - h[1]};
    const double R = std::hypot(a, b);
    const double s = *solve_planar_invariant(hh, kN, R);
    const double sin0 = s / kN[0], cos0 = std::sqrt(1 - sin0 * sin0);
    const double ex = R > 0 ? a / R : 1, ey = R > 0 ? b / R : 0;
    return std::array<double, 3>{sin0 * ex, sin0 * ey, cos0};
  };
  for (double R : {0.0, 0.003, 0.05, 0.2, 0.5}) {
    const double a = R * 0.6, b = R * 0.8;
    const double s = *solve_planar_invariant(h, kN, R);
    const double sink = s / kN[2], cosk = std::sqrt(1 - sink * sink);
    const double ex = R > 0 ? a / R : 1, ey = R > 0 ? b / R : 0;
    // Last leg direction (sin e, cos); u in its plane of incidence, v perpendicular: both ⊥ the leg.
    const std::array<double, 3> u{cosk * ex, cosk * ey, -sink}, v{-ey, ex, 0};
    const double delta = 1e-6;
    auto diff = [&](const std::array<double, 3>& w) {
      const auto p = d0_of(a + delta * w[0], b + delta * w[1], H + delta * w[2]);
      const auto m = d0_of(a - delta * w[0], b - delta * w[1], H - delta * w[2]);
      return std::array<double, 3>{(p[0] - m[0]) / (2 * delta), (p[1] - m[1]) / (2 * delta), (p[2] - m[2]) / (2 * delta)};
    };
    const auto d0 = d0_of(a, b, H), du = diff(u), dv = diff(v);
    const double det = d0[0] * (du[1] * dv[2] - du[2] * dv[1]) - d0[1] * (du[0] * dv[2] - du[2] * dv[0]) +
                       d0[2] * (du[0] * dv[1] - du[1] * dv[0]);
    const double g = planar_solid_angle_per_area(h, kN, s);
    EXPECT_NEAR(std::fabs(det) / g, 1.0, 1e-4) << "R " << R;
  }
  // One index everywhere: 1 / d².
  const std::array<double, 3> same{1, 1, 1};
  const double s = *solve_planar_invariant(h, same, 0.2);
  EXPECT_NEAR(planar_solid_angle_per_area(h, same, s) * (H * H + 0.04), 1.0, 1e-9);
}

// A glass wall (outer face x = 2.2 cm, inner x = 2 cm) of a huge cuvette; the
// solution absorbs at 420 nm (μ_a = 100 ln10 · 20000 · 5e-6 ≈ 23 /m); x at the origin.
// Everything but the shapes: a dye absorbing 380-480 nm in a solution, glass, and the
// glass-to-solution interface; `fluorescence` mode, excitation through glass = connect.
std::string dye_scene_head(const std::string& fluorescence) {
  return R"({
  "render": {"resolution": [4, 4], "spp": 1, "wavelengths": 1, "fluorescence": ")" + fluorescence + R"(",
             "excitation_through_glass": "connect"},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 0.01},
  "pigments": {"dye": {"extinction": {"table": {"lambda": [379.999, 380, 480, 480.001], "value": [0, 20000, 20000, 0]}},
                       "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}}},
  "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                "glass_to_solution": {"type": "dielectric", "ior": 0.8913}},
  "media": {"solution": {"solvent": "none", "pigments": [{"pigment": "dye", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
)";
}

std::string wall_scene(const std::string& light) {
  return dye_scene_head("direct") + R"(    {"type": "box", "min": [-1, -1, -1], "max": [0.022, 1, 1], "material": "glass"},
    {"type": "box", "min": [-0.98, -0.98, -0.98], "max": [0.02, 0.98, 0.98], "material": "glass_to_solution",
     "inside": "solution"})" + light + "}";
}
constexpr double kMuA = 100 * 2.302585092994046 * 20000 * 5e-6;
constexpr float kLambda = 420.f;

double fresnel_T(double cos_i, double eta) { return 1 - fresnel_dielectric(float(cos_i), float(eta)); }

TEST(SpecularConnection, CollimatedBeamThroughWallMatchesClosedForm) {
  // Oblique beam: s = n_air sin θ_air, irradiance across the beam scales by
  // cos θ_air / cos θ_0, Fresnel at both faces, Beer–Lambert over h0 / cos θ_0.
  const Scene scene = load_scene(write_scene("connect_distant", wall_scene(R"(],
  "lights": [{"type": "distant", "direction": [-1, -0.3, 0.2], "spectrum": {"gaussian": [420, 8]}, "scale": 3}])")));
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  Rng rng;
  const auto phi = connect_through_dielectrics(scene, Vec3(0.f), 0, 0, Point2{0.5f, 0.5f}, media, rng);
  ASSERT_TRUE(phi);
  const double cos_air = 1 / std::sqrt(1 + 0.09 + 0.04);
  const double s = kN[2] * std::sqrt(1 - cos_air * cos_air);
  const double cos1 = std::sqrt(1 - s * s / (kN[1] * kN[1])), cos0 = std::sqrt(1 - s * s);
  const double E = 3 * std::get<DistantLight>(scene.lights[0]).L(kLambda);
  const double expected = E * fresnel_T(cos0, kN[1] / kN[0]) * fresnel_T(cos1, kN[2] / kN[1]) * cos_air / cos0 *
                          std::exp(-kMuA * 0.02 / cos0);
  EXPECT_NEAR(*phi / expected, 1.0, 1e-4);
}

TEST(SpecularConnection, PointLightThroughWallMatchesReducedDistance) {
  // On axis the geometry term is 1 / (Σ h_i / n_i)² (paraxial reduced distance),
  // times (n_x / n_air)² for the radiance compressed into the solution.
  const Scene scene = load_scene(write_scene("connect_point", wall_scene(R"(],
  "lights": [{"type": "point", "position": [0.3, 0, 0], "spectrum": {"gaussian": [420, 8]}, "scale": 2}])")));
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  Rng rng;
  const auto phi = connect_through_dielectrics(scene, Vec3(0.f), 0, 0, Point2{0.5f, 0.5f}, media, rng);
  ASSERT_TRUE(phi);
  const double I = 2 * std::get<PointLight>(scene.lights[0]).I(kLambda);
  const double reduced = 0.02 / kN[0] + 0.002 / kN[1] + 0.278 / kN[2];
  const double expected = I * fresnel_T(1, kN[1]) * fresnel_T(1, kN[2] / kN[1]) * std::exp(-kMuA * 0.02) /
                          (kN[2] * kN[2] * reduced * reduced);
  EXPECT_NEAR(*phi / expected, 1.0, 1e-4);
}

TEST(SpecularConnection, AreaLightThroughWallMatchesForwardRefraction) {
  // Independent estimate: directions uniform over the hemisphere toward the
  // wall, refracted forward by Snell's law through the two faces, kept where
  // they land on the 10 cm panel at x = 30 cm. Agreement within 4σ.
  const Scene scene = load_scene(write_scene("connect_area", wall_scene(R"(,
    {"type": "quad", "corner": [0.3, -0.05, 0.05], "edge_u": [0, 0.1, 0], "edge_v": [0, 0, -0.1],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}])")));
  ASSERT_EQ(scene.lights.size(), 1u);
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  Rng rng(7, 0);
  Estimate connect, forward;
  for (int i = 0; i < 200000; ++i) {
    const auto phi = connect_through_dielectrics(scene, Vec3(0.f), 0, 0, Point2{rng.uniform(), rng.uniform()}, media, rng);
    ASSERT_TRUE(phi);
    connect.add(*phi);
  }
  const double Le = 5 * std::get<AreaLight>(scene.lights[0]).Le(kLambda);
  const std::array<double, 3> h{0.02, 0.002, 0.278};
  for (int i = 0; i < 4000000; ++i) {
    const double cos0 = rng.uniform(), phi_az = 2 * kPi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1 - cos0 * cos0));
    double value = 0;
    if (s < kN[2]) {
      const double r = planar_lateral_offset(h, kN, s);
      const double y = r * std::cos(phi_az), z = r * std::sin(phi_az);
      if (std::fabs(y) <= 0.05 && std::fabs(z) <= 0.05) {
        const double cos1 = std::sqrt(1 - s * s / (kN[1] * kN[1]));
        value = Le * fresnel_T(cos0, kN[1]) * fresnel_T(cos1, kN[2] / kN[1]) * std::exp(-kMuA * 0.02 / cos0) /
                (kN[2] * kN[2]) * (2 * kPi);
      }
    }
    forward.add(value);
  }
  const double sigma = std::hypot(connect.sigma(), forward.sigma());
  EXPECT_NEAR(connect.mean(), forward.mean(), 4 * sigma)
      << "connect " << connect.mean() << " ± " << connect.sigma() << ", forward " << forward.mean() << " ± "
      << forward.sigma();
  EXPECT_LT(forward.sigma(), 0.01 * forward.mean());
}

TEST(SpecularConnection, ContinuationThroughWallIsOwned) {
  // The solve from the straight line decides: a walk through the solved
  // vertices is solved from it; one with a vertex elsewhere (or a face left out) is not.
  const Scene scene = load_scene(write_scene("connect_owns", wall_scene(R"(,
    {"type": "quad", "corner": [0.3, -0.05, 0.05], "edge_u": [0, 0.1, 0], "edge_v": [0, 0, -0.1],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}])")));
  const Vec3 x(0.f), y(0.3f, 0.01f, 0.02f);
  const auto chain = straight_line_chain(scene, x, y, false);
  ASSERT_TRUE(chain);
  ASSERT_EQ(chain->count, 2);
  EXPECT_TRUE(chain->planar_parallel);
  const auto path = solve_refracted_path(scene, *chain, x, y, false, kLambda);
  ASSERT_TRUE(path);
  SpecularChain walked = *chain;
  for (int j = 0; j < 2; ++j) walked.faces[j] = path->face[j];
  EXPECT_TRUE(solved_deterministically(scene, x, y, walked, kLambda));
  EXPECT_FALSE(solved_deterministically(scene, x, y, *chain, kLambda)) << "the straight line's crossings are not the path";
  SpecularChain shorter = walked;
  shorter.count = 1;
  EXPECT_FALSE(solved_deterministically(scene, x, y, shorter, kLambda));
  SpecularChain other = walked;
  other.faces[1].p.y += 0.01f;
  EXPECT_FALSE(solved_deterministically(scene, x, y, other, kLambda));
  // Not a path at all: no random seed converges to it either.
  EXPECT_TRUE(seed_reachable_solution(scene, x, y, walked, kLambda));
  EXPECT_FALSE(seed_reachable_solution(scene, x, y, other, kLambda));
}

}  // namespace
}  // namespace chlorovdb::test

namespace chlorovdb::test {
namespace {

// Fluence at x from light 0 three ways: every continuation path (what `full`
// mode's continuation does: uniform directions, emitters skipped on the first
// segment; exact with excitation rays that stop at glass), the continuations
// by their share against the connection, and the connection by its share
// (a first continuation's origin: P_continue = 1/2).
struct PartitionEstimates {
  Estimate all, rest, connect;
  double sigma() const {
    return std::sqrt(all.sigma() * all.sigma() + rest.sigma() * rest.sigma() + connect.sigma() * connect.sigma());
  }
};
PartitionEstimates partition_estimates(const Scene& scene, const Vec3& x, int paths, int connections, uint64_t seed) {
  Rng rng(test_seed(seed), 0);
  PathStats stats;
  const ContinuationOrigin origin{x, 0, &scene.fluorescence[0][0], continuation_probability(0, 0)};
  auto continuation = [&](bool shared) {
    Estimate e;
    PathOptions options;
    options.skip_emitters_on_first_segment = true;
    options.continuation_origin = shared ? &origin : nullptr;
    for (int i = 0; i < paths; ++i) {
      SampledWavelengths wl = SampledWavelengths::single(kLambda);
      const Vec3 w = sample_uniform_sphere(Point2{rng.uniform(), rng.uniform()});
      const PathRadiance L = trace_path_from(scene, Ray{x, w}, 0, wl, rng, stats, options);
      e.add(double(L.other[0] + L.fluorescence[0]) * 4 * kPi);
    }
    return e;
  };
  PartitionEstimates p;
  p.all = continuation(false);
  p.rest = continuation(true);
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  for (int i = 0; i < connections; ++i)
    p.connect.add(
        *connect_through_dielectrics(scene, x, 0, 0, Point2{rng.uniform(), rng.uniform()}, media, rng, &origin));
  std::printf("fluence: all paths %.5g ± %.2g, continuations' share %.5g ± %.2g, connection's %.5g ± %.2g\n",
              p.all.mean(), p.all.sigma(), p.rest.mean(), p.rest.sigma(), p.connect.mean(), p.connect.sigma());
  return p;
}

// The partition's checks: all continuations = the ones not owned + the
// connection within 4σ, the connection far from zero, at most `rest_share` of
// the fluence left to continuations, and a precise enough reference.
void expect_partition(const PartitionEstimates& p, double rest_share) {
  EXPECT_NEAR(p.all.mean(), p.rest.mean() + p.connect.mean(), 4 * p.sigma());
  EXPECT_GT(p.connect.mean(), 10 * p.sigma());
  EXPECT_LT(p.rest.mean(), rest_share * p.all.mean());
  EXPECT_LT(p.all.sigma(), 0.05 * p.all.mean());
}

TEST(SpecularConnection, PartitionWithContinuationsCountsEachPathOnce) {
  // Fluence at x by paths in uniform directions (what `full` mode's
  // continuation does): all of them, against the ones the connection does not
  // own plus the connection's estimate. Agreement within 4σ; the owned share
  // must be most of it (the walls' reflections are the rest).
  const Scene scene = load_scene(write_scene("connect_partition", wall_scene(R"(,
    {"type": "quad", "corner": [0.3, -0.1, 0.1], "edge_u": [0, 0.2, 0], "edge_v": [0, 0, -0.2],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}])")));
  const PartitionEstimates p = partition_estimates(scene, Vec3(0.f), 400000, 100000, 11);
  expect_partition(p, 0.5);
}

// A tank under a 0.2 mm glass film (its free surface), a low glass rim standing
// in the air above it at x = 4–4.5 cm, y = 1–8 mm, and a panel 10 cm up. From
// x = 1 cm under the surface, the straight line to the panel's far part clips
// the rim, but the path refracted at the surface passes over it: a path through
// the film's two faces alone, as from deep in a beaker over its rim.
std::string rim_scene() {
  return dye_scene_head("full") + R"(    {"type": "box", "min": [-0.5, -0.1, -0.5], "max": [0.5, 0.0002, 0.5], "material": "glass"},
    {"type": "box", "min": [-0.49, -0.09, -0.49], "max": [0.49, 0, 0.49], "material": "glass_to_solution",
     "inside": "solution"},
    {"type": "box", "min": [0.04, 0.001, -0.2], "max": [0.045, 0.008, 0.2], "material": "glass"},
    {"type": "quad", "corner": [0, 0.1, -0.1], "edge_u": [0.4, 0, 0], "edge_v": [0, 0, 0.2],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}]})";
}
const Vec3 kUnderFilm(0.f, -0.01f, 0.f);

TEST(SpecularConnection, PathPastFacesTheStraightLineClipsIsOwned) {
  const Scene scene = load_scene(write_scene("connect_rim", rim_scene()));
  const Vec3 y(0.3f, 0.1f, 0.f);  // on the panel
  const auto chain = straight_line_chain(scene, kUnderFilm, y, false);
  ASSERT_TRUE(chain);
  ASSERT_EQ(chain->count, 4) << "the film's two faces, then the rim's two";
  SpecularChain film = *chain;
  film.count = 2;
  const auto path = solve_refracted_path(scene, film, kUnderFilm, y, false, kLambda);
  ASSERT_TRUE(path);
  // Over the rim: at x = 4 cm the air leg is above its top (8 mm).
  const Vec3 exit = path->face[1].p, d = path->dir[2];
  EXPECT_GT(exit.y + d.y * (0.04f - exit.x) / d.x, 0.008f);

  SpecularChain walked = film;
  for (int j = 0; j < 2; ++j) walked.faces[j] = path->face[j];
  EXPECT_TRUE(solved_deterministically(scene, kUnderFilm, y, walked, kLambda));
  SpecularChain other = walked;
  other.faces[1].p.x += 0.001f;
  EXPECT_FALSE(solved_deterministically(scene, kUnderFilm, y, other, kLambda));
}

TEST(SpecularConnection, PartitionCountsPathsPastFacesTheStraightLineClipsOnce) {
  // As PartitionWithContinuationsCountsEachPathOnce, under the film with the
  // rim. The connection must also own the paths over the rim: they are 2.6 % of
  // the fluence here (σ 0.13 %), and what it leaves besides them is under 0.1 %.
  const Scene scene = load_scene(write_scene("connect_rim_partition", rim_scene()));
  const PartitionEstimates p = partition_estimates(scene, kUnderFilm, 400000, 100000, 37);
  expect_partition(p, 0.01);
}

// A 4 cm cuvette (2 mm glass) and a panel at its side, 14 cm away and reaching
// well above it, as scenes/default.json's UVB tube. From the upper right of the
// solution the straight line to the panel crosses the left wall, but the panel
// also shines in through the lid at a grazing angle: refracted down at ~47°,
// that light reaches the point too.
std::string cuvette_scene() {
  return dye_scene_head("full") + R"(    {"type": "box", "min": [-0.022, 0, -0.022], "max": [0.022, 0.064, 0.022], "material": "glass"},
    {"type": "box", "min": [-0.02, 0.002, -0.02], "max": [0.02, 0.062, 0.02], "material": "glass_to_solution",
     "inside": "solution"},
    {"type": "quad", "corner": [-0.14, 0.01, -0.04], "edge_u": [0, 0.11, 0], "edge_v": [0, 0, 0.08],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}]})";
}
const Vec3 kUnderLid(0.01f, 0.05f, 0.f);

TEST(SpecularConnection, PathThroughTheLidIsSolvedAsAWall) {
  const Scene scene = load_scene(write_scene("connect_lid", cuvette_scene()));
  const Vec3 y(-0.14f, 0.09f, 0.f);  // on the panel
  const auto side = straight_line_chain(scene, kUnderLid, y, false);
  ASSERT_TRUE(side);
  ASSERT_EQ(side->count, 2) << "the left wall's two faces";
  const auto lid = straight_line_chain(scene, kUnderLid, Vec3(0.f, 0.07f, 0.f), false);
  ASSERT_TRUE(lid);
  ASSERT_EQ(lid->count, 2) << "the lid's two faces";
  const auto path = solve_refracted_path(scene, *lid, kUnderLid, y, false, kLambda);
  ASSERT_TRUE(path);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(path->face[j].p.y, j == 0 ? 0.062f : 0.064f, 1e-6f) << "vertex " << j << " on the lid";
    EXPECT_LT(std::fabs(path->face[j].p.x), 0.02f) << "vertex " << j << " within the lid";
  }
  // The lid is one of the vessel's walls the connection solves besides the
  // straight line's: the path is its, without a random seed.
  const DeterministicChains candidates = deterministic_chains(scene, kUnderLid, y, false, true, kLambda);
  EXPECT_EQ(candidates.count, 3) << "the straight line's chain and the walls toward the panel: the left one, the lid "
                                    "(no mirror: the floor would not totally reflect the panel seen from here)";
  SpecularChain walked = *lid;
  for (int j = 0; j < 2; ++j) walked.faces[j] = path->face[j];
  EXPECT_TRUE(solved_deterministically(scene, kUnderLid, y, walked, kLambda));
}

// A distant light up and to the left of the cuvette (toward it: (−0.857, 0.514, 0)):
// from (1, 4, 0) cm the straight line leaves through the left wall, and the beam
// also comes in through the lid. Both are planar walls of the vessel: each one's
// closed form (Fresnel at both faces, the beam's cross-section cos θ_air / cos θ₀,
// Beer–Lambert over the liquid leg), and their sum is the connection's, with no
// random seed.
TEST(SpecularConnection, DistantLightThroughTheWallsSumsEachWallsClosedForm) {
  const Scene scene = load_scene(write_scene("connect_walls_distant", dye_scene_head("direct") + R"(
    {"type": "box", "min": [-0.022, 0, -0.022], "max": [0.022, 0.064, 0.022], "material": "glass"},
    {"type": "box", "min": [-0.02, 0.002, -0.02], "max": [0.02, 0.062, 0.02], "material": "glass_to_solution",
     "inside": "solution"}],
  "lights": [{"type": "distant", "direction": [1, -0.6, 0], "spectrum": {"gaussian": [420, 8]}, "scale": 3}]})"));
  const Vec3 x(0.01f, 0.04f, 0.f);
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  Rng rng;
  const auto arriving = light_through_dielectrics(scene, ShadowOrigin{x, 0, nullptr}, 0, Point2{}, media, rng,
                                                  SeedPolicy{0.f, true});
  ASSERT_TRUE(arriving);
  EXPECT_EQ(arriving->count, 2) << "the left wall and the lid";
  double sum = 0;
  for (int i = 0; i < arriving->count; ++i) sum += arriving->paths[size_t(i)].L[0];
  const double E = 3 * std::get<DistantLight>(scene.lights[0]).L(kLambda);
  const auto through_wall = [&](double cos_air, double h0) {
    const double s = kN[2] * std::sqrt(1 - cos_air * cos_air);
    const double cos1 = std::sqrt(1 - s * s / (kN[1] * kN[1])), cos0 = std::sqrt(1 - s * s);
    return E * fresnel_T(cos0, kN[1] / kN[0]) * fresnel_T(cos1, kN[2] / kN[1]) * cos_air / cos0 *
           std::exp(-kMuA * h0 / cos0);
  };
  const double norm = std::sqrt(1 + 0.36);
  const double left = through_wall(1 / norm, 0.03), lid = through_wall(0.6 / norm, 0.022);
  EXPECT_NEAR(sum / (left + lid), 1.0, 1e-4) << "left wall " << left << ", lid " << lid;
}

TEST(SpecularConnection, PartitionCountsPathsThroughOtherFacesOnce) {
  // As PartitionWithContinuationsCountsEachPathOnce, under the cuvette's lid.
  // The light through the lid is the walls' solve; past the cuvette's other
  // faces it is the random seeds' to find, each at its own rate: a path found
  // with probability p is the connection's with probability 1 − (1 − p)^1024
  // and the continuation's otherwise, so the sum holds it once. Measured: left
  // to continuations 2.9 % (σ 0.3 %); 15.8 % with neither the seeds nor the walls.
  const Scene scene = load_scene(write_scene("connect_lid_partition", cuvette_scene()));
  const PartitionEstimates p = partition_estimates(scene, kUnderLid, 400000, 100000, 43);
  expect_partition(p, 0.05);
}

// 2 mm above the cuvette's floor, the panel's light also arrives mirrored in the
// floor's underside: in through the left wall, down through the liquid's floor
// into the glass, totally reflected at the glass's outer face (60° inside it,
// past the 42° critical angle), and up into the liquid again: five faces, one a
// mirror, which the connection solves as a chain of its own.
const Vec3 kNearTheFloor(0.01f, 0.004f, 0.f);

TEST(SpecularConnection, LightTheFloorMirrorsIsSolvedAsAMirrorChain) {
  const Scene scene = load_scene(write_scene("connect_floor_mirror", cuvette_scene()));
  const Vec3 y(-0.14f, 0.03f, 0.f);  // on the panel
  const DeterministicChains candidates = deterministic_chains(scene, kNearTheFloor, y, false, true, kLambda);
  const SpecularChain* mirror = nullptr;
  for (int i = 0; i < candidates.count; ++i)
    for (int j = 0; j < candidates.chains[size_t(i)].count; ++j)
      if (candidates.chains[size_t(i)].faces[size_t(j)].reflect) mirror = &candidates.chains[size_t(i)];
  ASSERT_NE(mirror, nullptr) << "a chain mirrored in the floor";
  ASSERT_EQ(mirror->count, 5)
      << "the liquid's floor, the glass's outer face (mirror), the liquid's floor, the left wall";
  EXPECT_TRUE(mirror->faces[1].reflect);
  const auto path = solve_refracted_path(scene, *mirror, kNearTheFloor, y, false, kLambda);
  ASSERT_TRUE(path);
  EXPECT_NEAR(path->face[1].p.y, 0.f, 1e-6f) << "the mirror vertex on the glass's outer floor";
  for (int j : {0, 2})
    EXPECT_NEAR(path->face[size_t(j)].p.y, 0.002f, 1e-6f) << "vertex " << j << " on the liquid's floor";
  EXPECT_NEAR(path->face[3].p.x, -0.02f, 1e-6f);
  EXPECT_NEAR(path->face[4].p.x, -0.022f, 1e-6f);
  // Total internal reflection: Fresnel's product is the four crossings' alone.
  double crossings = 1;
  for (int j : {0, 2, 3, 4}) {
    const double cos_i = std::fabs(dot(path->dir[size_t(j)], normalize(path->ns[size_t(j)])));
    crossings *= fresnel_T(cos_i, path->n[size_t(j) + 1] / path->n[size_t(j)]);
  }
  EXPECT_NEAR(path_fresnel(scene, *path, kLambda), crossings, 1e-4);
  SpecularChain walked = *mirror;
  for (int j = 0; j < 5; ++j) walked.faces[size_t(j)] = path->face[size_t(j)];
  EXPECT_TRUE(solved_deterministically(scene, kNearTheFloor, y, walked, kLambda));
}

TEST(SpecularConnection, PartitionNearTheCuvettesFloorCountsEachPathOnce) {
  // As PartitionWithContinuationsCountsEachPathOnce, near the floor, where the
  // floor's mirror image of the panel is the connection's too. Measured: left to
  // continuations 12 %; 30 % without the mirror chains (checked).
  const Scene scene = load_scene(write_scene("connect_floor_partition", cuvette_scene()));
  const PartitionEstimates p = partition_estimates(scene, kNearTheFloor, 400000, 100000, 47);
  expect_partition(p, 0.2);
}

// A tank of solution behind one glass surface (index 1.5 inside), a panel
// above it reaching past its right wall. Near that wall the point sees the
// panel twice: through the top, and mirrored in the wall by total internal
// reflection (light in through the top, steeply down onto the wall).
std::string tank_scene() {
  return dye_scene_head("full") + R"(    {"type": "box", "min": [-0.05, -0.05, -0.05], "max": [0.05, 0, 0.05], "material": "glass",
     "inside": "solution"},
    {"type": "quad", "corner": [0, 0.1, -0.05], "edge_u": [0.1, 0, 0], "edge_v": [0, 0, 0.1],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}]})";
}

TEST(SpecularConnection, PartitionCountsMirroredPathsOnce) {
  // As PartitionWithContinuationsCountsEachPathOnce, beside the tank's wall.
  // The mirrored paths are the wall's mirror chain's (deterministic_chains) and,
  // where it is not solved, the random seeds' (a seed reflects where the glass
  // would: always under total internal reflection), shared by the power
  // heuristic with the seeded density, the continuation's share including what
  // the seeds' count (capped at 64 for paths with a mirror vertex) misses.
  // Enough samples that dropping either side's weight fails (3 % of the
  // fluence, 9σ and 6σ, measured before the mirror chains). Measured: left to
  // continuations 1.1 %; 8.6 % without the mirror chains.
  const Scene scene = load_scene(write_scene("connect_tank_partition", tank_scene()));
  const PartitionEstimates p = partition_estimates(scene, Vec3(0.045f, -0.03f, 0.f), 6400000, 1600000, 47);
  expect_partition(p, 0.1);
}

}  // namespace
}  // namespace chlorovdb::test

// ---- Manifold solver: curved and smooth-shaded mesh glass ----
namespace chlorovdb::test {
namespace {

// A round flask: 5 mm glass around 4.5 cm of pigment solution, both smooth-shaded meshes.
std::string flask_scene(const std::string& light) {
  return dye_scene_head("full") + R"(    {"type": "mesh", "file": ")" + write_smooth_sphere("flask_glass", 0.05f) + R"(", "material": "glass"},
    {"type": "mesh", "file": ")" + write_smooth_sphere("flask_solution", 0.045f) + R"(", "material": "glass_to_solution",
     "inside": "solution"})" + light + "}";
}
const std::string kFlaskPanel = R"(,
    {"type": "quad", "corner": [0.3, -0.1, 0.1], "edge_u": [0, 0.2, 0], "edge_v": [0, 0, -0.2],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}])";
const Vec3 kInFlask(0.012f, 0.007f, -0.004f);

TEST(SpecularManifold, AgreesWithThePlanarClosedForm) {
  // The general solver on a chain of two parallel box faces: the same vertices
  // and geometry term as Snell's-invariant closed form, for finite and distant ends.
  const Scene scene = load_scene(write_scene("manifold_planar", wall_scene("]")));
  const Vec3 x(0.f);
  int compared = 0;
  for (const Vec3 y : {Vec3(0.3f, 0.f, 0.f), Vec3(0.3f, 0.01f, 0.02f), Vec3(0.25f, -0.2f, 0.1f), Vec3(0.1f, 0.15f, -0.12f)})
    for (const bool to_infinity : {false, true}) {
      const auto chain = straight_line_chain(scene, x, y, to_infinity);
      ASSERT_TRUE(chain);
      ASSERT_TRUE(chain->planar_parallel);
      const auto closed = solve_refracted_path(scene, *chain, x, y, to_infinity, kLambda);
      const auto manifold = solve_manifold_path(scene, *chain, x, y, to_infinity, kLambda);
      ASSERT_EQ(bool(closed), bool(manifold)) << "y " << y.x << ' ' << y.y << ' ' << y.z << " to_infinity " << to_infinity;
      if (!closed) continue;
      ++compared;
      ASSERT_EQ(manifold->count, 2);
      for (int j = 0; j < 2; ++j) {
        EXPECT_LE(length(manifold->face[j].p - closed->face[j].p), 1e-6f * length(y)) << "vertex " << j;
        EXPECT_EQ(manifold->face[j].shape_id, closed->face[j].shape_id);
      }
      for (int j = 0; j <= 2; ++j) EXPECT_LT(length(manifold->dir[j] - closed->dir[j]), 1e-6f) << "leg " << j;
      EXPECT_NEAR(manifold->geometry / closed->geometry, 1.0, 1e-6) << "to_infinity " << to_infinity;
    }
  EXPECT_GE(compared, 6);
}

// Unit direction of the solved path's first leg from x toward the light point y.
std::optional<Vec3> start_direction(const Scene& scene, const Vec3& x, const Vec3& y) {
  const auto chain = straight_line_chain(scene, x, y, false);
  if (!chain) return std::nullopt;
  const auto path = solve_refracted_path(scene, *chain, x, y, false, kLambda);
  if (!path) return std::nullopt;
  return path->dir[0];
}

TEST(SpecularManifold, SmoothSphereGeometryTermMatchesFiniteDifferences) {
  // dω_0/dA_⊥ against central differences of the start direction when y moves
  // by ±δ along two axes perpendicular to the last leg (solid angle = |∂ω/∂a × ∂ω/∂b|).
  const Scene scene = load_scene(write_scene("manifold_fd", flask_scene("]")));
  for (const Vec3 y : {Vec3(0.3f, 0.f, 0.f), Vec3(0.3f, 0.05f, -0.03f), Vec3(0.2f, 0.15f, 0.1f), Vec3(-0.1f, 0.05f, 0.25f)}) {
    const auto chain = straight_line_chain(scene, kInFlask, y, false);
    ASSERT_TRUE(chain);
    ASSERT_EQ(chain->count, 2);
    EXPECT_FALSE(chain->planar_parallel);
    const auto path = solve_refracted_path(scene, *chain, kInFlask, y, false, kLambda);
    ASSERT_TRUE(path) << "y " << y.x << ' ' << y.y << ' ' << y.z;
    // Snell at the shading normals: η_a w_a + η_b w_b has no tangential part.
    for (int j = 0; j < 2; ++j) {
      const Vec3 h = float(path->n[j]) * -path->dir[j] + float(path->n[j + 1]) * path->dir[j + 1];
      const Vec3 tangential = h - path->ns[j] * dot(h, path->ns[j]);
      EXPECT_LT(length(tangential), 1e-5f) << "vertex " << j;
      EXPECT_LT(std::fabs(length(path->face[j].p) - (j == 0 ? 0.045f : 0.05f)), 2e-4f) << "on the mesh";
    }
    const Frame frame = Frame::from_z(path->dir[2]);
    // Small enough that y's neighbours keep x_1, x_2 on their triangles (the
    // interpolated normals' derivatives jump across edges), large against float rounding.
    const float delta = 2e-4f;
    std::array<Vec3, 2> d_omega;
    for (int q = 0; q < 2; ++q) {
      const Vec3 e = q == 0 ? frame.s : frame.t;
      const auto plus = start_direction(scene, kInFlask, y + e * delta);
      const auto minus = start_direction(scene, kInFlask, y - e * delta);
      ASSERT_TRUE(plus && minus);
      d_omega[q] = (*plus - *minus) / (2 * delta);
    }
    const double fd = length(cross(d_omega[0], d_omega[1]));
    EXPECT_NEAR(path->geometry / fd, 1.0, 2e-3) << "y " << y.x << ' ' << y.y << ' ' << y.z;
    std::printf("geometry term %.6g, finite differences %.6g\n", path->geometry, fd);
  }
}

TEST(SpecularManifold, SmoothFlaskConnectionPartitionsContinuationsExactly) {
  // Fluence at a point inside a round flask (two smooth-shaded mesh
  // interfaces) from a panel: all continuation paths (full + block, exact)
  // against the ones the connection does not own plus the connection. Agreement
  // within 4σ; the connection carries most of it (so a double count, or
  // dropping paths it does not produce, is many σ away).
  const Scene scene = load_scene(write_scene("manifold_partition", flask_scene(kFlaskPanel)));
  const PartitionEstimates p = partition_estimates(scene, kInFlask, 300000, 100000, 23);
  expect_partition(p, 0.3);
}

TEST(SpecularManifold, SpotLightThroughSmoothFlaskMatchesASmallDisk) {
  // A spot light behind curved glass has no other strategy; its connection must
  // equal the limit of a small area light of the same intensity toward x (disk
  // of radius 2 mm, I = Le · A · cos θ), whose connection the partition test
  // checks against continuations. The spot's edge (cone 30°, falloff 10°) is
  // placed so x sees it partly dimmed.
  const Vec3 p_light(0.3f, 0.05f, -0.03f);
  const Scene scene = load_scene(write_scene("manifold_spot", flask_scene(R"(,
    {"type": "disk", "center": [0.3, 0.05, -0.03], "normal": [-1, -0.15, 0.1], "radius": 0.002,
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 5}}],
  "lights": [{"type": "spot", "position": [0.3, 0.05, -0.03], "look_at": [0.05, -0.09, 0.04], "cone_angle": 30,
              "falloff_angle": 10, "spectrum": {"gaussian": [420, 8]}, "scale": 2e-5}])")));
  ASSERT_EQ(scene.lights.size(), 2u);
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);
  Rng rng(test_seed(5), 0);
  const auto spot = connect_through_dielectrics(scene, kInFlask, 0, 1, Point2{0.5f, 0.5f}, media, rng);
  ASSERT_TRUE(spot);
  ASSERT_GT(*spot, 0.f);
  Estimate disk;
  for (int i = 0; i < 20000; ++i)
    disk.add(*connect_through_dielectrics(scene, kInFlask, 0, 0, Point2{rng.uniform(), rng.uniform()}, media, rng));
  const auto chain = straight_line_chain(scene, kInFlask, p_light, false);
  ASSERT_TRUE(chain);
  const auto path = solve_refracted_path(scene, *chain, kInFlask, p_light, false, kLambda);
  ASSERT_TRUE(path);
  const float falloff = spot_falloff(std::get<SpotLight>(scene.lights[1]), -path->dir[2]);
  EXPECT_GT(falloff, 0.05f);
  EXPECT_LT(falloff, 0.95f);
  const double cos_disk = std::fabs(dot(normalize(Vec3(-1.f, -0.15f, 0.1f)), path->dir[2]));
  const double expected_ratio = 2e-5 * falloff / (5 * scene.geometry.area(2) * cos_disk);
  EXPECT_NEAR(*spot / disk.mean(), expected_ratio, (4 * disk.sigma() / disk.mean() + 1e-3) * expected_ratio)
      << "spot " << *spot << ", disk " << disk.mean() << " ± " << disk.sigma();
}


// Track length of the ray o + t d, t > 0, inside the sphere (c, r).
double chord_in_sphere(const Vec3& o, const Vec3& d, const Vec3& c, double r) {
  const Vec3 oc = o - c;
  const double b = dot(oc, d), q = dot(oc, oc) - r * r;
  const double disc = b * b - q;
  if (disc <= 0) return 0;
  const double t1 = -b - std::sqrt(disc), t2 = -b + std::sqrt(disc);
  return std::max(0.0, t2 - std::max(t1, 0.0));
}

// A photon through smooth glass with transmission forced at every face, its
// weight multiplied by 1 − R there (as the connections count): the ray leaving
// the last of `faces` transmissions, or nullopt when it escapes or is totally
// reflected first (not a transmission-only path).
std::optional<Ray> transmit_through_glass(const Scene& scene, Ray ray, SampledWavelengths wl, int faces,
                                          double* weight) {
  for (int crossed = 0; crossed < faces; ++crossed) {
    const auto hit = scene.geometry.intersect(ray, kInfinity);
    if (!hit) return std::nullopt;
    const Bsdf bsdf = make_bsdf(scene.materials[scene.shapes[hit->shape_id].material], *hit, wl);
    const auto bs = bsdf.sample(-ray.d, 1.f - 1e-7f, Point2{0.5f, 0.5f});
    if (!bs || !bs->is_transmission) return std::nullopt;
    *weight *= bs->f[0] * std::fabs(dot(bs->wi, hit->ns)) * bs->eta * bs->eta;  // 1 − R
    ray = scene.geometry.spawn_ray(*hit, bs->wi);
  }
  return ray;
}

// A photon from a point light at y (intensity I) through a glass ball of radius
// r at the origin: a direction uniform over the cone that just holds the ball
// (pdf 1 / (2π (1 − cos θ))), then transmit_through_glass through its two
// faces. *weight = I / pdf · Π(1 − R); nullopt when it misses or reflects.
std::optional<Ray> photon_through_ball(const Scene& scene, const Vec3& y, double I, double r,
                                       const SampledWavelengths& wl, Rng& rng, double* weight) {
  const double cos_cone = std::sqrt(1 - 1.005 * r * 1.005 * r / double(dot(y, y)));
  const double cos_t = 1 - rng.uniform() * (1 - cos_cone), phi = 2 * M_PI * rng.uniform();
  const double sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
  const Vec3 d = normalize(Frame::from_z(normalize(-y)).to_world(
      Vec3(float(sin_t * std::cos(phi)), float(sin_t * std::sin(phi)), float(cos_t))));
  *weight = I * 2 * M_PI * (1 - cos_cone);
  return transmit_through_glass(scene, Ray{y, d}, wl, 2, weight);
}

TEST(SpecularManifold, PointLightThroughAGlassBallMatchesPhotonsFromTheLight) {
  // A smooth glass ball (mesh, r = 2 cm) and a point light 20 cm from it. The
  // fluence rate its refracted paths bring to a point x behind the ball, against
  // photons traced from the light through the ball (directions uniform over the
  // cone that holds the ball, transmission forced with weight 1 − R at each
  // face, as the connection counts) and scored by their track length in a
  // sphere of radius 3 mm around x. Two points:
  // - beside the ball's shadow: the straight line to the light misses the ball,
  //   so every refracted path is one the straight-line seed cannot find (only
  //   SMS's random seeds reach it; without them the connection returns the
  //   direct term alone);
  // - inside the shadow: the straight line crosses the ball; its solution and
  //   the random seeds' must not be counted twice.
  // Agreement within 4σ of both estimates combined, plus 1 % for the photon
  // sphere's finite size (the fluence varies across its 3 mm).
  const Scene scene = load_scene(write_scene("manifold_ball", dye_scene_head("direct") + R"(    {"type": "mesh", "file": ")" +
                                                                   write_smooth_sphere("glass_ball", 0.02f) +
                                                                   R"(", "material": "glass"}],
  "lights": [{"type": "point", "position": [0.2, 0, 0], "spectrum": {"gaussian": [420, 8]}, "scale": 2}]})"));
  const Vec3 y(0.2f, 0.f, 0.f);
  const double I = 2 * std::get<PointLight>(scene.lights[0]).I(kLambda);
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  PreparedMedia media(scene, wl);

  constexpr double kScoreRadius = 0.003;
  const std::array<Vec3, 2> points{Vec3(-0.2f, 0.05f, 0.01f), Vec3(-0.15f, 0.012f, -0.006f)};
  std::array<Estimate, 2> photons;
  Rng rng(test_seed(41), 0);
  constexpr int kPhotons = 1000000;
  for (int i = 0; i < kPhotons; ++i) {
    double weight;
    const auto out = photon_through_ball(scene, y, I, 0.02, wl, rng, &weight);
    for (size_t k = 0; k < points.size(); ++k)
      photons[k].add(out ? weight * chord_in_sphere(out->o, out->d, points[k], kScoreRadius) /
                               (4.0 / 3 * M_PI * std::pow(kScoreRadius, 3))
                         : 0.0);
  }

  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3& x = points[k];
    const auto straight = straight_line_chain(scene, x, y, false);
    ASSERT_TRUE(straight);
    EXPECT_EQ(straight->count, k == 0 ? 0 : 2) << "point " << k;
    // The direct term (beside the shadow) is exact: take it out of the connection.
    const double direct = k == 0 ? I / double(dot(y - x, y - x)) : 0.0;
    Estimate connect;
    for (int i = 0; i < 20000; ++i)
      connect.add(*connect_through_dielectrics(scene, x, -1, 0, Point2{0.5f, 0.5f}, media, rng) - direct);
    const double sigma = std::hypot(connect.sigma(), photons[k].sigma());
    std::printf("point %zu: connection %.5g ± %.2g, photons %.5g ± %.2g (direct %.5g)\n", k, connect.mean(),
                connect.sigma(), photons[k].mean(), photons[k].sigma(), direct);
    EXPECT_GT(photons[k].mean(), 20 * photons[k].sigma()) << "point " << k << " must lie in the refracted beam";
    EXPECT_NEAR(connect.mean(), photons[k].mean(), 4 * sigma + 0.01 * photons[k].mean()) << "point " << k;
  }
}

TEST(SpecularManifold, FloorBehindAGlassBallMatchesPhotonsFromTheLight) {
  // The caustic a point light casts through glass on a diffuse floor, as camera
  // paths see it: next-event estimation from the floor connects through the ball
  // (render.direct_light_through_glass = connect), against photons traced from
  // the light through the ball (as in the test above) and scored by the
  // irradiance they bring to a disk of radius 1.5 mm around x on the floor:
  // L = ρ/π · E_photons, the camera's estimate averaged over the same disk, less
  // ρ/π · I cos θ / d² where the straight line to the light misses the ball
  // (exact). max_depth 1 keeps the floor's direct light alone. Three disks: two
  // in the shadow, where the ball focuses the light (the straight line crosses
  // the ball: its solution and the random seeds' must not be counted twice),
  // and one beside the shadow, lit directly and through the ball (only random
  // seeds find that). Agreement within 4σ of both estimates combined. With
  // "block", or without the random seeds, the camera gets nothing there.
  const std::string scene_json = R"({
  "render": {"resolution": [4, 4], "spp": 1, "wavelengths": 1, "max_depth": 1},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 0.01},
  "materials": {"glass": {"type": "dielectric", "ior": 1.5}, "floor": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [
    {"type": "mesh", "file": ")" + write_smooth_sphere("floor_ball", 0.02f) +
                                 R"(", "material": "glass"},
    {"type": "box", "min": [-1, -1, -1.06], "max": [1, 1, -0.06], "material": "floor"}],
  "lights": [{"type": "point", "position": [0.02, 0.01, 0.2], "spectrum": {"gaussian": [420, 8]}, "scale": 2}]})";
  const Scene scene = load_scene(write_scene("floor_ball", scene_json));
  const Vec3 y(0.02f, 0.01f, 0.2f);
  const double I = 2 * std::get<PointLight>(scene.lights[0]).I(kLambda);
  const SampledWavelengths wl = SampledWavelengths::single(kLambda);
  constexpr float kFloor = -0.06f;
  constexpr double kDiskRadius = 0.0015;
  const std::array<Vec3, 3> points{Vec3(-0.008f, -0.003f, kFloor), Vec3(-0.004f, -0.004f, kFloor),
                                   Vec3(-0.035f, -0.02f, kFloor)};
  std::array<Estimate, 3> photons;
  Rng rng(test_seed(43), 0);
  constexpr int kPhotons = 2000000;
  for (int i = 0; i < kPhotons; ++i) {
    double weight;
    const auto out = photon_through_ball(scene, y, I, 0.02, wl, rng, &weight);
    const auto hit = out ? scene.geometry.intersect(*out, kInfinity) : std::nullopt;
    for (size_t k = 0; k < points.size(); ++k) {
      const bool in_disk = hit && std::fabs(hit->p.z - kFloor) < 1e-4f && length(hit->p - points[k]) < kDiskRadius;
      photons[k].add(in_disk ? weight / (M_PI * kDiskRadius * kDiskRadius) : 0.0);
    }
  }

  // The camera looks at points uniform over the same disk from the side, missing the ball.
  const Vec3 w = normalize(Vec3(0.8f, 0.4f, 0.45f));
  for (size_t k = 0; k < points.size(); ++k) {
    Estimate camera;
    PathStats stats;
    int straight_faces = -1;
    for (int i = 0; i < 20000; ++i) {
      const Point2 u = sample_uniform_disk_concentric(Point2{rng.uniform(), rng.uniform()});
      const Vec3 x = points[k] + Vec3(float(kDiskRadius) * u.x, float(kDiskRadius) * u.y, 0.f);
      const auto straight = straight_line_chain(scene, x + Vec3(0.f, 0.f, 1e-5f), y, false);
      ASSERT_TRUE(straight);
      straight_faces = straight->count;
      const double d2 = dot(y - x, y - x);
      const double direct = straight->count == 0 ? I * (y.z - x.z) / std::sqrt(d2) / d2 : 0.0;
      SampledWavelengths lambda = wl;
      camera.add(trace_path(scene, Ray{x + w, -w}, -1, lambda, rng, stats).other[0] - 0.5 / M_PI * direct);
    }
    const double expected = 0.5 / M_PI * photons[k].mean(), expected_sigma = 0.5 / M_PI * photons[k].sigma();
    const double sigma = std::hypot(camera.sigma(), expected_sigma);
    std::printf("point %zu (%d faces on the straight line): camera %.5g ± %.2g, photons %.5g ± %.2g\n", k,
                straight_faces, camera.mean(), camera.sigma(), expected, expected_sigma);
    EXPECT_GT(photons[k].mean(), 20 * photons[k].sigma()) << "point " << k << " must lie in the refracted light";
    EXPECT_NEAR(camera.mean(), expected, 4 * sigma) << "point " << k;
  }
}

TEST(SpecularManifold, FloorCausticOfAnAreaLightThroughAGlassBallAgreesWithBsdfSampling) {
  // render.direct_light_through_glass = all: the floor's next-event estimation also
  // solves for the paths through the ball to a point on a small area light, and
  // the path tracer drops the BSDF-sampled paths the connection owns. Against
  // "connect" (the area light through glass from BSDF-sampled paths alone, exact):
  // the floor's radiance at two points, one in the ball's focused shadow (the
  // straight line to the light crosses the ball) and one beside it (the paths
  // through the ball lie off the straight line: no deterministic solve finds
  // them, so BSDF sampling keeps them), within 4σ of both combined. A connection
  // counted on top of the BSDF paths it owns fails it; and the connection must
  // carry the light.
  const auto scene_with = [](const std::string& mode) {
    return load_scene(write_scene("area_ball_" + mode, R"({
  "render": {"resolution": [4, 4], "spp": 1, "wavelengths": 1, "max_depth": 3,
             "direct_light_through_glass": ")" + mode + R"("},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 0.01},
  "materials": {"glass": {"type": "dielectric", "ior": 1.5}, "floor": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [
    {"type": "mesh", "file": ")" + write_smooth_sphere("area_ball", 0.02f) +
                                               R"(", "material": "glass"},
    {"type": "box", "min": [-1, -1, -1.06], "max": [1, 1, -0.06], "material": "floor"},
    {"type": "quad", "corner": [0.0, -0.01, 0.2], "edge_u": [0, 0.03, 0], "edge_v": [0.03, 0, 0],
     "emission": {"spectrum": {"gaussian": [420, 8]}, "scale": 2}}]})"));
  };
  const Scene all = scene_with("all"), connect = scene_with("connect");
  ASSERT_EQ(all.settings.direct_light_through_glass, DirectLightThroughGlass::all);
  const Vec3 w = normalize(Vec3(0.8f, 0.4f, 0.45f));  // the camera's view of the floor, missing the ball
  const std::array<Vec3, 2> points{Vec3(-0.006f, -0.002f, -0.06f), Vec3(-0.03f, -0.02f, -0.06f)};
  Rng rng(test_seed(53), 0);
  for (size_t k = 0; k < points.size(); ++k) {
    std::array<Estimate, 2> radiance;
    for (int m = 0; m < 2; ++m) {
      const Scene& scene = m == 0 ? all : connect;
      PathStats stats;
      for (int i = 0; i < (m == 0 ? 20000 : 200000); ++i) {
        SampledWavelengths lambda = SampledWavelengths::single(kLambda);
        radiance[size_t(m)].add(trace_path(scene, Ray{points[k] + w, -w}, -1, lambda, rng, stats).other[0]);
      }
    }
    const double sigma = std::hypot(radiance[0].sigma(), radiance[1].sigma());
    std::printf("point %zu: all %.5g ± %.2g (20k paths), connect %.5g ± %.2g (200k paths)\n", k, radiance[0].mean(),
                radiance[0].sigma(), radiance[1].mean(), radiance[1].sigma());
    EXPECT_GT(radiance[1].mean(), 10 * radiance[1].sigma()) << "point " << k << " must see the light through the ball";
    EXPECT_NEAR(radiance[0].mean(), radiance[1].mean(), 4 * sigma) << "point " << k;
    // In the shadow the straight line's solve carries the light: per path, far
    // less noise than BSDF sampling.
    if (k == 0)
      EXPECT_LT(radiance[0].sigma() * std::sqrt(20000.0), 0.1 * radiance[1].sigma() * std::sqrt(200000.0))
          << "per-path noise";
  }
}

TEST(SpecularConnection, DirectLightLanesFollowTheGlassDispersion) {
  // Every lane a camera path carries gets the light of the hero's refracted
  // path: with constant-index glass each lane as if it were traced alone; with
  // Sellmeier glass (each λ bent its own way) the hero alone, standing for all
  // lanes (×4, as SampledWavelengths::terminate_secondary), or for itself once
  // the path's secondary wavelengths are already terminated.
  const auto ball_scene = [](const std::string& name, const std::string& ior) {
    return load_scene(write_scene(name, R"({
  "render": {"resolution": [4, 4], "spp": 1, "wavelengths": 4},
  "camera": {"type": "orthographic", "position": [0, 0, 2], "look_at": [0, 0, 0], "height": 0.01},
  "materials": {"glass": {"type": "dielectric", "ior": )" + ior + R"(}},
  "shapes": [{"type": "mesh", "file": ")" + write_smooth_sphere(name, 0.02f) +
                                             R"(", "material": "glass"}],
  "lights": [{"type": "spot", "position": [0.02, 0.01, 0.2], "look_at": [0, 0, 0], "cone_angle": 30,
              "spectrum": {"gaussian": [500, 60]}}]})"));
  };
  const Scene constant = ball_scene("lanes_constant", "1.5");
  const Scene sellmeier = ball_scene(
      "lanes_sellmeier", R"({"sellmeier": {"B": [1.03961212, 0.231792344, 1.01046945], "C": [0.00600069867, 0.0200179144, 103.560653]}})");
  const std::array<float, 4> lambdas{450, 500, 550, 600}, pdfs{0.01f, 0.01f, 0.01f, 0.01f};
  const ShadowOrigin x{Vec3(-0.004f, -0.003f, -0.06f), -1, nullptr};
  const auto arrive = [&](const Scene& scene, const SampledWavelengths& wl) {
    PreparedMedia media(scene, wl);
    Rng rng(test_seed(47), 0);  // the same draws for every call: the same random seeds
    const auto a = light_through_dielectrics(scene, x, 0, Point2{}, media, rng);
    EXPECT_TRUE(a && a->count >= 1);
    return a.value_or(ArrivingLight{});  // on failure: no paths, so the checks below fail, not crash
  };
  const SampledWavelengths four = SampledWavelengths::from_values(lambdas.data(), pdfs.data(), 4);
  const ArrivingLight all = arrive(constant, four);
  ASSERT_GT(all.paths[0].L[0], 0.f);
  for (int i = 0; i < 4; ++i) {
    const ArrivingLight alone = arrive(constant, SampledWavelengths::single(lambdas[i]));
    ASSERT_EQ(alone.count, all.count);
    for (int p = 0; p < all.count; ++p) EXPECT_NEAR(all.paths[p].L[i], alone.paths[p].L[0], 1e-5f * alone.paths[p].L[0]);
  }
  const ArrivingLight hero = arrive(sellmeier, SampledWavelengths::single(lambdas[0]));
  const ArrivingLight dispersed = arrive(sellmeier, four);
  SampledWavelengths terminated = four;
  terminated.terminate_secondary();
  const ArrivingLight hero_only = arrive(sellmeier, terminated);
  ASSERT_EQ(dispersed.count, hero.count);
  for (int p = 0; p < hero.count; ++p) {
    EXPECT_NEAR(dispersed.paths[p].L[0], 4 * hero.paths[p].L[0], 1e-5f * hero.paths[p].L[0]);
    EXPECT_NEAR(hero_only.paths[p].L[0], hero.paths[p].L[0], 1e-5f * hero.paths[p].L[0]);
    for (int i = 1; i < 4; ++i) EXPECT_EQ(dispersed.paths[p].L[i], 0.f) << "lane " << i;
  }
}

// Energy share of transmission-only paths the solver does not find: from points
// inside a vessel's liquid, uniform directions refracted forward through the
// glass by the path tracer's own dielectric (transmission forced, weight
// Π(1 − R)) to where they leave (an opaque surface, or 10 m out when they
// escape); a path counts as found when a deterministic solve toward that end
// point returns it (solved_deterministically). For area lights
// continuations carry the share not found; for delta lights SMS's random seeds
// do, so the share none of kSeeds random seeds reaches either bounds what a
// delta light misses (a solution reached with probability p < 1/kSeeds may be
// counted as unreached). Measured (docs/fluorescence.md): not found by the
// straight line flask 1.5 %, beaker 11.7 %, teapot 12.5 %, mostly straight
// lines that cross another number of faces than the path. The bounds sit a
// little above: a solver that gives up on converging solves (a Newton early
// stop at a 0.3 gain instead of 0.9 reads 2.9 %, 13.3 %, 14.8 %) fails them.
constexpr int kSeeds = 256;
struct MissedShare {
  double missed = 0, unreached = 0, total = 0;
  long paths = 0;
};
MissedShare transmission_paths_missed(const Scene& scene, int liquid_shape, float depth, int points, uint64_t seed) {
  Rng rng(test_seed(seed), 0);
  MissedShare share;
  SampledWavelengths wl = SampledWavelengths::single(kLambda);
  for (int i = 0; i < points; ++i) {
    const ShapeSample ss = scene.geometry.sample_area(liquid_shape, Point2{rng.uniform(), rng.uniform()});
    const Vec3 x = ss.p - ss.n * (depth * (0.1f + 0.9f * rng.uniform()));
    Ray ray{x, sample_uniform_sphere(Point2{rng.uniform(), rng.uniform()})};
    SpecularChain walked;
    double weight = 1;
    std::optional<Vec3> end;
    for (int crossings = 0; crossings < 64 && walked.count <= kMaxSpecularChain; ++crossings) {
      const auto hit = scene.geometry.intersect(ray, kInfinity);
      if (!hit) {
        end = ray.o + ray.d * 10.f;
        break;
      }
      const ShapeBinding& b = scene.shapes[hit->shape_id];
      if (is_pass_through(scene, b)) {
        ray = scene.geometry.spawn_ray(*hit, ray.d);
        continue;
      }
      if (!std::holds_alternative<Dielectric>(scene.materials[b.material])) {
        end = hit->p;
        break;
      }
      const Bsdf bsdf = make_bsdf(scene.materials[b.material], *hit, wl);
      const auto bs = bsdf.sample(-ray.d, 1.f - 1e-7f, Point2{0.5f, 0.5f});
      if (!bs || !bs->is_transmission || walked.count == kMaxSpecularChain) break;  // total internal reflection
      weight *= bs->f[0] * std::fabs(dot(bs->wi, hit->ns)) * bs->eta * bs->eta;  // 1 − R
      walked.faces[walked.count++] = ChainFace{hit->shape_id, hit->prim_id, hit->ng, dot(hit->ng, hit->p), hit->p};
      ray = scene.geometry.spawn_ray(*hit, bs->wi);
    }
    if (!end || walked.count == 0) continue;
    ++share.paths;
    share.total += weight;
    if (solved_deterministically(scene, x, *end, walked, kLambda)) continue;
    share.missed += weight;
    // Left to SMS's random seeds: does any of kSeeds converge to it?
    const float tolerance = 1e-4f * length(*end - x);
    bool reached = false;
    for (int s = 0; s < kSeeds && !reached; ++s) {
      const auto path = solve_from_random_seed(scene, x, *end, false, kLambda, true, rng);
      reached = path && path->count == walked.count;
      for (int j = 0; reached && j < walked.count; ++j)
        reached = path->face[j].shape_id == walked.faces[j].shape_id &&
                  length(path->face[j].p - walked.faces[j].p) <= tolerance;
    }
    if (!reached) share.unreached += weight;
  }
  return share;
}

TEST(SpecularManifold, FindsTheTransmissionPathsOfVesselGlass) {
  struct Vessel {
    std::string name;
    Scene scene;
    float depth;   // x lies up to this far inside the liquid's surface, metres
    double bound;            // the share not found from the straight line must stay below this
    double unreached_bound;  // and the share no random seed reaches below this
  };
  const auto source = std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes";
  std::vector<Vessel> vessels;
  vessels.push_back({"smooth flask", load_scene(write_scene("manifold_missed", flask_scene("]"))), 0.02f, 0.02, 0.005});
  vessels.push_back({"beaker", load_scene(source / "glass_UVB_5uM_Q0.23.json"), 0.01f, 0.13, 0.04});
  vessels.push_back({"teapot", load_scene(source / "teapot_50uM_D65_UVB_aim2.json"), 0.01f, 0.14, 0.03});
  for (const Vessel& v : vessels) {
    int liquid = -1;
    for (size_t s = 0; s < v.scene.shapes.size(); ++s)
      if (v.scene.shapes[s].medium_inside >= 0 && v.scene.shapes[s].material >= 0) liquid = int(s);
    ASSERT_GE(liquid, 0) << v.name;
    const MissedShare share = transmission_paths_missed(v.scene, liquid, v.depth, 20000, 29);
    const double missed = share.missed / share.total, unreached = share.unreached / share.total;
    std::printf("%s: %ld transmission-only paths, energy share not found from the straight line %.4f, "
                "nor by %d random seeds %.4f\n", v.name.c_str(), share.paths, missed, kSeeds, unreached);
    EXPECT_GT(share.paths, 2000) << v.name;
    EXPECT_LT(missed, v.bound) << v.name;
    EXPECT_LT(unreached, v.unreached_bound) << v.name;
  }
}

}  // namespace
}  // namespace chlorovdb::test
