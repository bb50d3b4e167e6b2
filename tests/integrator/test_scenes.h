#pragma once
// Scenes for integrator tests, written as JSON so the loader is exercised too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh.h"
#include "integrator/path_tracer.h"
#include "scene/scene_loader.h"
#include "scratch_dir.h"
#include "test_seed.h"

namespace chlorovdb::test {

inline std::filesystem::path write_scene(const std::string& name, const std::string& json) {
  const auto path = scratch_dir("integrator_tests") / (name + ".json");
  std::ofstream(path) << json;
  return path;
}

// A smooth-shaded latitude/longitude sphere (vertex normals) as an OBJ file; the
// coarser it is, the more its interpolated normals disagree with its faces.
inline std::string write_smooth_sphere(const std::string& name, float radius, int rings = 24, int segments = 48) {
  const TriangleMesh mesh = make_uv_sphere(Vec3(0.f), radius, rings, segments);
  const auto path = scratch_dir("integrator_tests") / (name + ".obj");
  std::ofstream out(path);
  out.precision(9);
  for (const Vec3& p : mesh.positions) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
  for (const Vec3& n : mesh.normals) out << "vn " << n.x << ' ' << n.y << ' ' << n.z << '\n';
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    out << 'f';
    for (int k = 0; k < 3; ++k) out << ' ' << mesh.indices[3 * t + k] + 1 << "//" << mesh.indices[3 * t + k] + 1;
    out << '\n';
  }
  return path.string();
}

// The head of a centimetre scene of a UVB-only dye (absorbing 280–330 nm,
// emitting at 650 nm) in `solution`, with a grey `floor`, `glass`,
// `glass_to_solution` and an index-matched `boundary`, up to its open shapes
// array; `render_keys` are added to the render block (`full` mode).
inline std::string uvb_dye_scene_head(const std::string& render_keys) {
  return R"({
  "length_unit": "cm",
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": "full", "max_depth": 16,
             )" +
         render_keys + R"(},
  "camera": {"type": "orthographic", "position": [0, 3, 20], "look_at": [0, 3, 0], "height": 6},
  "pigments": {"dye": {"extinction": {"table": {"lambda": [279.999, 280, 330, 330.001],
                                                "value": [0, 20000, 20000, 0]}},
                       "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}}},
  "materials": {"floor": {"type": "diffuse", "albedo": 0.5},
                "glass": {"type": "dielectric", "ior": 1.5},
                "glass_to_solution": {"type": "dielectric", "ior": 0.8913},
                "boundary": {"type": "interface"}},
  "media": {"solution": {"solvent": {"rayleigh": false},
                         "pigments": [{"pigment": "dye", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
)";
}

// Mean and standard error of a scalar estimator.
struct Estimate {
  static constexpr long kBatch = 10000;
  double sum = 0, sum2 = 0;
  long n = 0;
  std::vector<double> batch_means;  // of consecutive batches of kBatch samples
  double batch_sum = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
    batch_sum += x;
    if (n % kBatch == 0) batch_means.push_back(std::exchange(batch_sum, 0.0) / kBatch);
  }
  double mean() const { return sum / n; }
  double sigma() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / n); }
  // The standard error without a few rare spikes: 1.4826 × the median absolute
  // deviation of the batch means (a normal law's σ) over √batches. Batches of 10⁴
  // paths: one spike moves one batch, which the median ignores, while an estimator
  // whose noise is all rare hits (one in a few thousand paths) still reads about
  // its sample σ. Twenty batches leave it noisy itself (±30 %).
  double typical_sigma() const {
    std::vector<double> m = batch_means;
    if (m.size() < 2) return sigma();
    const auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    const double centre = median(m);
    for (double& v : m) v = std::abs(v - centre);
    return 1.4826 * median(m) / std::sqrt(double(m.size()));
  }
};

// Mean fluorescence over four red lanes (640-670 nm) along one camera ray, from
// `paths` paths whose streams are (test_seed(seed), i).
inline Estimate red_fluorescence_along(const Scene& scene, const Ray& ray, int paths, uint64_t seed) {
  constexpr float kLambdas[4] = {640.f, 650.f, 660.f, 670.f};
  const float pdf[4] = {1, 1, 1, 1};
  Estimate e;
  PathStats stats;
  for (int i = 0; i < paths; ++i) {
    Rng rng(test_seed(seed), uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(kLambdas, pdf, 4);
    const PathRadiance L = trace_path(scene, ray, scene.camera_medium, lambda, rng, stats);
    e.add(L.fluorescence.average(4));
  }
  return e;
}

// Slab of pigment solution, index-matched (interface box), thickness D metres,
// wide enough that its edges do not matter, lit at normal incidence by a
// distant light travelling along -z onto the face z = D. The pigment absorbs
// only where the light shines (a table that ends before the emission band).
struct SlabSetup {
  double D = 0.01;             // m
  double concentration = 20;   // µM
  double epsilon = 20000;      // L/mol/cm, flat over [eps_lo, eps_hi]
  double eps_lo = 380, eps_hi = 480;
  std::string light = "{\"gaussian\": [420, 8]}";
  double Q = 0.5;
  std::string mode = "direct";
  std::string render_extra;  // more `render` keys, e.g. R"(, "quantum_yield_mode": "roulette")"
};

inline std::string slab_scene_json(const SlabSetup& s) {
  char buf[4096];
  std::snprintf(buf, sizeof buf, R"({
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": "%s", "max_depth": 64%s},
  "camera": {"type": "orthographic", "position": [0, 0, 1], "look_at": [0, 0, 0], "height": 0.01},
  "pigments": {"dye": {
    "extinction": {"table": {"lambda": [%g, %g, %g, %g], "value": [0, %g, %g, 0]}},
    "quantum_yield": %g, "emission": {"gaussian": [650, 10]}}},
  "materials": {"boundary": {"type": "interface"}},
  "media": {"solution": {"solvent": "none",
    "pigments": [{"pigment": "dye", "concentration": %g, "unit": "uM"}]}},
  "shapes": [{"type": "box", "min": [-10, -10, 0], "max": [10, 10, %g],
              "material": "boundary", "inside": "solution"}],
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": %s, "scale": 1}]
})",
                s.mode.c_str(), s.render_extra.c_str(), s.eps_lo - 1e-3, s.eps_lo, s.eps_hi, s.eps_hi + 1e-3, s.epsilon, s.epsilon, s.Q,
                s.concentration, s.D, s.light.c_str());
  return buf;
}

}  // namespace chlorovdb::test
