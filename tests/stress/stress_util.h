#pragma once
// Numerical stress tests (issue 7): tiny scenes at the extremes of every input
// range, rendered through the public path (JSON scene file -> load_scene ->
// render -> Film). Each render must
//   1. terminate within a time bound (a watchdog aborts the test binary with the
//      case's name when it does not: a hang is reported, never waited out);
//   2. put no NaN or Inf on the film: Film::nonfinite_samples() == 0 (the
//      renderer drops and counts them, so a non-zero count is a bug upstream of
//      the film) and every value of every image layer finite;
//   3. stay within an energy bound (luminance_bound below) where one exists.
#include "scratch_dir.h"
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <typeinfo>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "spectra/color.h"

namespace chlorovdb::stress {

// Sanitizer builds run 3-10x slower: their time bounds scale with it.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr double kTimeScale = 8.0;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr double kTimeScale = 8.0;
#else
inline constexpr double kTimeScale = 1.0;
#endif
#else
inline constexpr double kTimeScale = 1.0;
#endif

inline double time_scale() {
  const char* env = std::getenv("CHLOROVDB_STRESS_TIME_SCALE");  // e.g. on a loaded machine
  const double extra = env ? std::atof(env) : 1.0;
  return kTimeScale * (extra > 0 ? extra : 1.0);
}

// Aborts the process (so CTest reports the test as failed, with this message)
// if it is still alive `seconds` after construction.
class Watchdog {
 public:
  Watchdog(std::string what, double seconds) : what_(std::move(what)), seconds_(seconds * time_scale()) {
    thread_ = std::thread([this] {
      std::unique_lock lock(mutex_);
      if (!cv_.wait_for(lock, std::chrono::duration<double>(seconds_), [this] { return done_; })) {
        std::fprintf(stderr, "\nWATCHDOG: %s did not finish within %.0f s: unbounded loop or runaway cost\n",
                     what_.c_str(), seconds_);
        std::fflush(stderr);
        std::_Exit(124);
      }
    });
  }
  ~Watchdog() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

 private:
  std::string what_;
  double seconds_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

inline std::filesystem::path scratch_dir() { return test::scratch_dir("stress_tests"); }

inline std::filesystem::path write_scene(const std::string& name, const std::string& json) {
  const auto path = scratch_dir() / (name + ".json");
  std::ofstream(path) << json;
  return path;
}

// Replaces each "$KEY" of `text` (longest keys first is the caller's job: keys must not prefix each other).
inline std::string subst(std::string text, const std::vector<std::pair<std::string, std::string>>& values) {
  for (const auto& [key, value] : values)
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
      text.replace(at, key.size(), value);
  return text;
}

// Shortest round-trip text of a number, for JSON.
inline std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// The stress suite's test dye: decadic molar extinction flat over the whole range
// (so it absorbs its own emission: absorption and emission overlap everywhere).
inline constexpr double kDyeEpsilon = 1e4;                              // L mol^-1 cm^-1
inline constexpr double kSigmaPerMolar = 100 * 2.302585 * kDyeEpsilon;  // 1/m per mol/L (docs/physics.md §1)

// Image size, wavelengths per path and path depth of a dye_cube render.
struct DyeCubeRender {
  int resolution = 8;
  int wavelengths = 4;
  int max_depth = 16;
};

// A 1 m cube of the dye (index-matched) holding `field` (the pigment entry's concentration
// or grid), a grey floor, a white environment.
inline std::string dye_cube(const std::string& field, double Q, const std::string& mode, const std::string& scatter = "",
                            DyeCubeRender r = {}) {
  return subst(R"({
  "render": {"resolution": [$RES, $RES], "wavelengths": $WL, "fluorescence": "$MODE", "max_depth": $DEPTH},
  "camera": {"position": [0.4, 0.6, 3], "look_at": [0, 0, 0], "fov": 40},
  "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 830], "value": [$EPS, $EPS]}},
                       "quantum_yield": $Q, "emission": {"gaussian": [650, 20]}}},
  "materials": {"boundary": {"type": "interface"}, "floor": {"type": "diffuse", "albedo": 0.8}},
  "media": {"dye": {"solvent": "none", "pigments": [{"pigment": "dye", $FIELD}] $SCATTER}},
  "shapes": [{"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "boundary", "inside": "dye"},
             {"type": "quad", "corner": [-3, -0.5, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0], "material": "floor"}],
  "lights": [{"type": "environment", "spectrum": 1}]
})",
               {{"$RES", std::to_string(r.resolution)}, {"$WL", std::to_string(r.wavelengths)},
                {"$DEPTH", std::to_string(r.max_depth)}, {"$MODE", mode}, {"$EPS", num(kDyeEpsilon)},
                {"$Q", num(Q)}, {"$FIELD", field}, {"$SCATTER", scatter}});
}

// ---------------------------------------------------------------------------
// Energy bound.
//
// Y(R) is luminance, normalised so that a constant spectrum of 1 has Y = 1.
// Every light is reduced to an equivalent radiance spectrum R_l: area and
// environment lights emit radiance scale·S; a distant light of irradiance
// scale·S lights a white Lambertian surface to radiance scale·S/π (its
// fluorescence is bounded the same way, below). Point and spot lights have no
// radiance bound (irradiance grows as 1/r² near them): scenes with them get
// no energy check, only the finiteness and time checks.
//
// Passive transport (albedo <= 1, dielectrics, non-emitting media) is a
// weighted average of emitted radiance with total weight <= 1, so the camera
// (in vacuum) sees luminance <= max_l Y(R_l).
//
// Fluorescence adds, per unit length of a ray, j(λ) <= Q f(λ)/(4π) ∫ (λ'/λ) μ_a(λ') Φ(λ') dλ'
// with Φ <= 4π R. Integrated along a ray the absorbed part is bounded by the
// incident R times the geometric concentration of the medium's shape (the
// ratio of its longest chord to its mean chord: 2.6 for a cube; we allow
// K = 4), the photon-to-energy factor λ'/λ by 830/250, and the luminance of
// emission concentrated at the peak of ȳ by ȳ_max / ∫ȳ dλ = 1/106.857 nm.
// So luminance <= max_l Y(R_l) + K·(830/250)/106.857 · Q_max · Σ_l ∫ R_l dλ.
// This is loose (it is a blow-up detector, not a physics check: the
// fluorescence slab tests pin the physics), but every term is an upper bound.
// Thin sheets viewed edge-on can concentrate fluorescence beyond K (the
// luminescent-concentrator effect): stress scenes use compact shapes.
// ---------------------------------------------------------------------------
inline double luminance_bound(const Scene& scene, double K = 4.0) {
  double y_max = 0, radiance_integral = 0, q_max = 0;
  for (const Light& light : scene.lights) {
    const bool is_distant = std::holds_alternative<DistantLight>(light);
    if (std::holds_alternative<PointLight>(light) || std::holds_alternative<SpotLight>(light))
      return std::numeric_limits<double>::infinity();
    const double factor = light_scale(light) / (is_distant ? kPi : 1.0);
    const Spectrum& S = emission_spectrum(light);
    y_max = std::max(y_max, factor * luminance(S));
    radiance_integral += factor * S.integral(kLambdaMinUV, kLambdaMax);
  }
  for (const auto& medium : scene.fluorescence)
    for (const FluorescentPigment& fp : medium) q_max = std::max(q_max, double(fp.quantum_yield));
  return y_max + K * (kLambdaMax / kLambdaMinUV) / 106.857 * q_max * radiance_integral;
}

inline double pixel_luminance(const std::vector<float>& rgb, size_t pixel) {
  // Linear sRGB (D65) to CIE Y.
  return 0.2126729 * rgb[3 * pixel] + 0.7151522 * rgb[3 * pixel + 1] + 0.0721750 * rgb[3 * pixel + 2];
}

struct RenderCase {
  std::string name;          // names the input in every failure message
  std::string json;          // the scene
  SceneOverrides overrides;  // e.g. transmittance estimator, fluorescence mode
  int spp = 8;
  int threads = 1;
  double seconds = 10;       // watchdog bound (scaled under sanitizers)
  bool check_energy = true;  // only where luminance_bound is finite
  int spectral_bins = 0;
  double pixel_noise_factor = 4;  // a single pixel's mean may exceed the bound by MC noise at low spp
};

struct RenderOutcome {
  Image image;
  uint64_t nonfinite = 0;
  double seconds = 0;
  double bound = 0;
  double max_luminance = 0, mean_luminance = 0;
  RenderStats stats;
};

// Loads and renders one case under a watchdog, and checks the three properties.
inline RenderOutcome render_case(const RenderCase& c) {
  RenderOutcome out;
  Watchdog watchdog(c.name, c.seconds);
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = load_scene(write_scene(c.name, c.json), c.overrides);
  Film film(scene.settings.width, scene.settings.height, film_layer_names(), ColorSpace::sRGB);
  if (c.spectral_bins > 0) film.enable_spectral(kLambdaMin, kLambdaMax, c.spectral_bins);
  RenderOptions options;
  options.spp = c.spp;
  options.threads = c.threads;
  options.seed = 1;
  out.stats = chlorovdb::render(scene, film, options);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.nonfinite = film.nonfinite_samples();
  out.image = film.to_image(out.stats.samples_done);

  EXPECT_EQ(out.stats.samples_done, c.spp) << c.name;
  EXPECT_EQ(out.nonfinite, 0u) << c.name << ": " << out.nonfinite << " non-finite samples reached the film ("
                               << out.stats.paths.paths << " camera paths)";
  for (const ImageLayer& layer : out.image.layers) {
    size_t bad = 0, first = 0;
    for (size_t i = 0; i < layer.pixels.size(); ++i)
      if (!std::isfinite(layer.pixels[i]) && bad++ == 0) first = i;
    EXPECT_EQ(bad, 0u) << c.name << ": layer " << layer.name << " has " << bad << " non-finite values (first at "
                       << first << ")";
  }

  const std::vector<float>& total = out.image.layers[kLayerTotal].pixels;
  const size_t pixels = size_t(out.image.width) * size_t(out.image.height);
  double sum = 0;
  for (size_t p = 0; p < pixels; ++p) {
    const double y = pixel_luminance(total, p);
    out.max_luminance = std::max(out.max_luminance, y);
    sum += y;
  }
  out.mean_luminance = sum / double(pixels);
  out.bound = luminance_bound(scene);
  if (c.check_energy && std::isfinite(out.bound)) {
    EXPECT_LE(out.mean_luminance, 1.05 * out.bound + 1e-6)
        << c.name << ": image mean luminance above the energy bound";
    EXPECT_LE(out.max_luminance, c.pixel_noise_factor * out.bound + 1e-6)
        << c.name << ": a pixel's luminance is above " << c.pixel_noise_factor << "x the energy bound";
  }
  return out;
}

// render_case for sweeps: an exception fails this case (named) and the sweep goes on.
inline std::optional<RenderOutcome> try_case(const RenderCase& c) {
  try {
    return render_case(c);
  } catch (const std::exception& e) {
    ADD_FAILURE() << c.name << ": " << typeid(e).name() << ": " << e.what();
  }
  return std::nullopt;
}

inline double layer_sum(const RenderOutcome& o, int layer) {
  double s = 0;
  for (float v : o.image.layers[size_t(layer)].pixels) s += std::fabs(v);
  return s;
}

}  // namespace chlorovdb::stress
