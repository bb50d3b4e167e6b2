#include "scene/scene_loader.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include <fmt/format.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/number.h"
#include "fluorescence/emission_spectrum.h"
#include "scene/medium_param.h"
#include "scene/param_reader.h"
#include "scene/spectrum_param.h"
#include "spectra/color.h"
#include "spectra/library.h"

namespace chlorovdb {

namespace {

// Name -> index tables with "did you mean" on a miss.
class NameTable {
 public:
  void add(const std::string& name, int index) { index_[name] = index; }
  bool contains(const std::string& name) const { return index_.count(name) != 0; }
  int find(ParamReader& params, const std::string& key, const std::string& what) const {
    const std::string name = params.require_string(key);
    const auto it = index_.find(name);
    if (it != index_.end()) return it->second;
    std::vector<std::string> names;
    for (const auto& [n, i] : index_) names.push_back(n);
    const std::string near = nearest_word(name, names);
    params.fail(key, fmt::format("no {} of that name{}", what, near.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", near)));
  }

 private:
  std::map<std::string, int> index_;
};

// A grid more than this factor smaller or larger than the rest of the scene gets a warning.
constexpr float kGridScaleWarning = 100.f;

float length_unit_in_metres(ParamReader& top) {
  return metres_per_length_unit(top.get_enum("length_unit", "m", kLengthUnits));
}

const std::vector<std::string> kFluorescenceModes{"auto", "direct", "full", "reference", "off"};
const std::vector<std::string> kEstimators{"auto", "ratio", "residual_ratio", "delta"};

void check_choice(const std::string& flag, const std::string& value, const std::vector<std::string>& choices) {
  if (std::find(choices.begin(), choices.end(), value) != choices.end()) return;
  const std::string near = nearest_word(value, choices);
  throw InputError("command line", flag, value,
                   fmt::format("must be one of {}{}", fmt::join(choices, ", "),
                               near.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", near)));
}

// `names` as an AOV mask; an unknown name is an error about `key` naming it and the nearest AOV.
AovMask read_aov_names(const std::vector<std::string>& names, const std::function<void(const std::string&)>& fail) {
  std::string unknown;
  const AovMask mask = aov_mask(names, &unknown);
  if (!unknown.empty()) {
    const std::string near = nearest_word(unknown, aov_names());
    fail(fmt::format("\"{}\" is not an AOV: expected any of {}{}", unknown, fmt::join(aov_names(), ", "),
                     near.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", near)));
  }
  return mask;
}

RenderSettings read_render_settings(ParamReader& top, const SceneOverrides& o, std::string* fluorescence,
                                    std::string* transmittance) {
  RenderSettings s;
  if (auto r = top.optional_child("render")) {
    const auto res = r->get_floats("resolution", {512.f, 512.f}, 2);
    if (res.size() != 2 || res[0] < 1 || res[1] < 1 || res[0] > kMaxImageSide || res[1] > kMaxImageSide ||
        res[0] != std::floor(res[0]) || res[1] != std::floor(res[1]))
      r->fail("resolution", fmt::format("expected [width, height], whole numbers in [1, {}]", kMaxImageSide));
    s.width = int(res[0]);
    s.height = int(res[1]);
    s.spp = r->get_int("spp", s.spp, 1, kMaxSpp);
    s.max_depth = r->get_int("max_depth", s.max_depth, 0, 100000);
    s.wavelengths = r->get_int("wavelengths", s.wavelengths, 1, kMaxWavelengths);
    s.seed = r->get_uint64("seed", 0);
    s.color_space = r->get_enum("color_space", "srgb", {"srgb", "acescg"}) == "acescg" ? ColorSpace::ACEScg
                                                                                        : ColorSpace::sRGB;
    s.exposure = r->get_float("exposure", 0.f, -40.f, 40.f);
    *transmittance = r->get_enum("transmittance", "auto", kEstimators);
    *fluorescence = r->get_enum("fluorescence", "auto", kFluorescenceModes);
    s.spectral_bins = r->get_int("spectral_bins", 0, 0, 4096);
    if (r->has("aovs")) {
      const nlohmann::json& v = r->raw("aovs");
      std::vector<std::string> names;
      if (v.is_array())
        for (const auto& e : v) names.push_back(e.is_string() ? e.get<std::string>() : e.dump());
      if (!v.is_array()) r->fail("aovs", fmt::format("expected an array of names, any of {}", fmt::join(aov_names(), ", ")));
      s.aovs = read_aov_names(names, [&](const std::string& problem) { r->fail("aovs", problem); });
    }
    s.skip_unneeded_work = r->get_bool("skip_unneeded_work", true);
    const std::string glass = r->get_enum("excitation_through_glass", "connect", {"connect", "fresnel", "block"});
    s.excitation_through_glass = glass == "fresnel" ? ExcitationThroughGlass::fresnel
                                 : glass == "block" ? ExcitationThroughGlass::block
                                                    : ExcitationThroughGlass::connect;
    {
      const std::string direct = r->get_enum("direct_light_through_glass", "connect", {"connect", "block", "all"});
      s.direct_light_through_glass = direct == "block" ? DirectLightThroughGlass::block
                                     : direct == "all" ? DirectLightThroughGlass::all
                                                       : DirectLightThroughGlass::connect;
    }
    s.excitation_bounce = r->get_bool("excitation_bounce", true);
    s.continuation_directions =
        r->get_enum("continuation_directions", "uniform", {"uniform", "guided"}) == "guided"
            ? ContinuationDirections::guided
            : ContinuationDirections::uniform;
    s.excitation_estimate = r->get_enum("excitation_estimate", "rays", {"rays", "photons"}) == "photons"
                                ? ExcitationEstimate::photons
                                : ExcitationEstimate::rays;
    s.excitation_photons = r->get_int("excitation_photons", int(s.excitation_photons), 1, 1 << 30);
    s.excitation_grid_cells = r->get_int("excitation_grid_cells", s.excitation_grid_cells, 1, 64);
    s.excitation_photons_aimed = r->get_float("excitation_photons_aimed", s.excitation_photons_aimed, 0.f, 0.99f);
    s.camera_wavelengths = r->get_enum("camera_wavelengths", "scene", {"scene", "visible"}) == "visible"
                               ? CameraWavelengths::visible
                               : CameraWavelengths::scene;
    s.excitation_sampling = r->get_enum("excitation_sampling", "importance", {"importance", "uniform"}) == "uniform"
                                ? ExcitationSampling::uniform
                                : ExcitationSampling::importance;
    s.quantum_yield_mode = r->get_enum("quantum_yield_mode", "weight", {"weight", "roulette"}) == "roulette"
                               ? QuantumYieldMode::roulette
                               : QuantumYieldMode::weight;
    r->finish();
  } else {
    *transmittance = "auto";
    *fluorescence = "auto";
  }
  // Film: 3 layers × XYZ doubles plus the spectral bins, twice (a per-pass film).
  const auto refuse_huge_film = [&](int w, int h) {
    check_memory(2.0 * w * h * (3 * 3 + s.spectral_bins + (s.aovs ? Film::kAovSums : 0)) * 8.0, "the image (resolution and spectral bins)",
                 top.file().string(), "render.resolution", fmt::format("[{}, {}]", w, h));
  };
  if (o.width) s.width = *o.width;
  if (o.height) s.height = *o.height;
  if (o.spp) s.spp = *o.spp;
  if (o.wavelengths) s.wavelengths = *o.wavelengths;
  if (o.seed) s.seed = *o.seed;
  if (o.transmittance) check_choice("--transmittance", *transmittance = *o.transmittance, kEstimators);
  if (o.fluorescence) check_choice("--fluorescence", *fluorescence = *o.fluorescence, kFluorescenceModes);
  if (o.aovs) {
    std::vector<std::string> names;
    for (size_t start = 0; start < o.aovs->size();) {
      const size_t comma = std::min(o.aovs->find(',', start), o.aovs->size());
      if (comma > start) names.push_back(o.aovs->substr(start, comma - start));
      start = comma + 1;
    }
    s.aovs = read_aov_names(names, [&](const std::string& problem) { throw InputError("command line", "--aovs", *o.aovs, problem); });
  }
  refuse_huge_film(s.width, s.height);
  s.transmittance_auto = *transmittance == "auto";
  if (!s.transmittance_auto) s.transmittance = *transmittance_estimator_from_string(*transmittance);
  return s;
}

// "sensors": {"name": {"region": [x0, y0, x1, y1]}}: whole pixel indices with
// x0 < x1 <= width, y0 < y1 <= height of the image being rendered.
std::vector<Sensor> read_sensors(ParamReader& top, const RenderSettings& s) {
  std::vector<Sensor> sensors;
  for (auto& [name, sensor] : top.children_map("sensors")) {
    const std::vector<float> r = sensor.get_floats("region", {});
    if (r.size() != 4) sensor.fail("region", "expected [x0, y0, x1, y1] (pixels, x1 and y1 exclusive)");
    for (float v : r)
      if (v != std::floor(v)) sensor.fail("region", "pixel indices must be whole numbers");
    if (r[0] < 0 || r[1] < 0 || r[2] > s.width || r[3] > s.height)
      sensor.fail("region", fmt::format("lies outside the {}x{} image", s.width, s.height));
    if (!(r[0] < r[2] && r[1] < r[3])) sensor.fail("region", "needs x0 < x1 and y0 < y1 (an empty or inverted region)");
    sensor.finish();
    sensors.push_back({name, int(r[0]), int(r[1]), int(r[2]), int(r[3])});
  }
  return sensors;
}

// The camera; its eye and target points (metres) go to *eye and *target.
Camera read_camera(ParamReader& top, const RenderSettings& s, float unit, Vec3* eye_out, Vec3* target_out) {
  ParamReader c = top.child("camera");
  const std::string type = c.get_enum("type", "perspective", {"perspective", "orthographic"});
  const Vec3 eye = c.require_vec3("position") * unit;
  const Vec3 target = c.require_vec3("look_at") * unit;
  const Vec3 up = c.get_vec3("up", {0, 1, 0});
  if (length(target - eye) == 0.f) c.fail("look_at", "must differ from \"position\"");
  if (!std::isfinite(length(target - eye)))
    c.fail("look_at", "is too far from \"position\" for single precision (their distance overflows)");
  if (length(up) == 0.f) c.fail("up", "must not be the zero vector");
  *eye_out = eye;
  *target_out = target;
  Transform world_from_camera;
  try {
    world_from_camera = Transform::look_at(eye, target, up);
  } catch (const std::domain_error& e) {
    c.fail("up", e.what());
  }
  Camera::Projection projection;
  if (type == "perspective") {
    PerspectiveCamera p;
    p.world_from_camera = world_from_camera;
    p.fov_degrees = c.get_float("fov", 40.f, 1e-3f, 179.9f);
    p.lens_radius = c.get_float("lens_radius", 0.f, 0.f) * unit;
    p.focus_distance = c.get_float("focus_distance", length(target - eye) / unit, 1e-9f) * unit;
    projection = p;
  } else {
    projection = OrthographicCamera{world_from_camera, c.get_float("height", 1.f, 1e-12f) * unit};
  }
  c.finish();
  return Camera(projection, s.width, s.height);
}

Material read_material(ParamReader& m) {
  const std::string type = m.get_enum("type", "diffuse", {"diffuse", "dielectric", "interface"});
  Material result = Interface{};
  if (type == "diffuse") {
    const Spectrum albedo = read_spectrum(m, "albedo", Spectrum::constant(0.5f));
    if (albedo.max_value() > 1.f) m.fail("albedo", "reflectance must not exceed 1 at any wavelength");
    result = Diffuse{albedo};
  } else if (type == "dielectric") {
    Dielectric d{1.5f};
    if (m.has("ior") && m.raw("ior").is_object()) {
      ParamReader ior = m.child("ior");
      ParamReader sm = ior.child("sellmeier");
      const auto B = sm.get_floats("B", {}, 3), C = sm.get_floats("C", {}, 3);
      if (B.size() != 3 || C.size() != 3) sm.fail("", "needs three B and three C coefficients");
      d.ior = Sellmeier{{B[0], B[1], B[2]}, {C[0], C[1], C[2]}};
      if (const auto problem = sellmeier_problem(std::get<Sellmeier>(d.ior), kLambdaMinUV, kLambdaMax))
        sm.fail("", *problem);
      sm.finish();
      ior.finish();
    } else {
      d.ior = m.get_float("ior", 1.5f, 1e-3f, 10.f);
    }
    result = d;
  }
  m.finish();
  return result;
}

Transform read_transform(ParamReader& shape, float unit) {
  auto t = shape.optional_child("transform");
  if (!t) return {};
  Transform result;
  try {
    if (t->has("scale")) {
      if (t->raw("scale").is_number()) result = Transform::scale(Vec3(t->require_float("scale")));
      else result = Transform::scale(t->require_vec3("scale"));
    }
    if (t->has("rotate")) {
      const auto r = t->get_floats("rotate", {}, 4);
      if (r.size() != 4) t->fail("rotate", "expected [degrees, axis_x, axis_y, axis_z]");
      result = Transform::rotate(r[0], {r[1], r[2], r[3]}) * result;
    }
    if (t->has("translate")) result = Transform::translate(t->require_vec3("translate") * unit) * result;
  } catch (const std::domain_error& e) {
    t->fail("", e.what());
  }
  t->finish();
  return result;
}

// Positions given in the file's length unit: scale object space to metres first.
TriangleMesh read_shape_mesh(ParamReader& sh, const std::string& type, float unit) {
  switch (type[0]) {
    case 'q':
      return make_quad(sh.require_vec3("corner") * unit, sh.require_vec3("edge_u") * unit,
                       sh.require_vec3("edge_v") * unit);
    case 'b': {
      Bounds3 b;
      b.lo = sh.require_vec3("min") * unit;
      b.hi = sh.require_vec3("max") * unit;
      if (b.empty()) sh.fail("max", "must be greater than \"min\" on every axis");
      return make_box(b);
    }
    case 'd':
      return make_disk(sh.get_vec3("center", {}) * unit, sh.get_vec3("normal", {0, 1, 0}),
                       sh.require_float("radius", 1e-30f) * unit, 64);
    default: {
      const auto path = sh.require_path("file");
      MeshLoadInfo info;
      TriangleMesh mesh = load_mesh(path, &info);
      if (unit != 1.f) mesh = transform_mesh(std::move(mesh), Transform::scale(Vec3(unit)));
      return mesh;
    }
  }
}

Light read_light(ParamReader& l, float unit) {
  const std::string type = l.get_enum("type", "point", {"point", "spot", "distant", "environment"});
  Spectrum spectrum = read_spectrum(l, "spectrum", named_spectrum("D65"));
  const float scale = l.get_float("scale", 1.f, 0.f);
  if (l.get_bool("normalize", false)) {
    const float Y = luminance(spectrum);
    if (!(Y > 0.f)) l.fail("normalize", "the spectrum has no luminance (it emits nothing visible)");
    spectrum = spectrum.scaled(1.f / Y);
  }
  // Radiance is carried in single precision; path weights divide by small
  // densities (up to ~1e15 here), so emission beyond ~1e20 would overflow.
  constexpr float kMaxEmission = 1e20f;
  if (scale * spectrum.max_value() > kMaxEmission)
    l.fail("scale", fmt::format("emission up to {:.3g} would overflow single-precision radiance (limit {:.0e}); only "
                                "ratios between lights matter, so scale them all down",
                                scale * spectrum.max_value(), kMaxEmission));
  Light light = PointLight{};
  if (type == "point") {
    light = PointLight{l.require_vec3("position") * unit, spectrum, scale};
  } else if (type == "spot") {
    const Vec3 p = l.require_vec3("position") * unit;
    const Vec3 target = l.require_vec3("look_at") * unit;
    if (!(length(target - p) > 0.f) || !std::isfinite(length(target - p)))
      l.fail("look_at", "must differ from \"position\" (the spot light's axis points from position to look_at)");
    const float cone = l.get_float("cone_angle", 30.f, 1e-3f, 180.f);
    const float falloff = l.get_float("falloff_angle", 5.f, 0.f, cone);
    const float deg = kPi / 180.f;
    light = SpotLight{p, target - p, std::cos((cone - falloff) * deg), std::cos(cone * deg), spectrum, scale};
  } else if (type == "distant") {
    const Vec3 d = l.require_vec3("direction");
    if (!(length(d) > 0.f) || !std::isfinite(length(d))) l.fail("direction", "must be a non-zero, finite vector");
    light = DistantLight{normalize(d), spectrum, scale};
  } else {
    light = EnvironmentLight{spectrum, scale};
  }
  l.finish();
  return light;
}

// Light-selection weight: emitted power (times `share`), computed at unit scale
// and multiplied in double, so scales from 1e-30 to 1e30 neither overflow nor
// vanish; only ratios matter, so the weights are rescaled to a maximum of 1.
double light_power(const Light& light, const GeometryScene& geometry, float lambda_min_nm, float lambda_max_nm) {
  Light unit_scale = light;
  std::visit([](auto& l) { l.scale = 1.f; }, unit_scale);
  return double(phi_power(unit_scale, geometry, lambda_min_nm, lambda_max_nm)) * light_scale(light);
}

std::vector<float> relative_weights(const std::vector<double>& w) {
  double max = 0;
  for (double x : w) max = std::max(max, std::isfinite(x) ? x : 0.0);
  std::vector<float> r(w.size(), 0.f);
  for (size_t i = 0; i < w.size(); ++i) r[i] = max > 0 && std::isfinite(w[i]) ? float(w[i] / max) : 0.f;
  return r;
}

// Does any fluorescent pigment of the scene emit where `absorber` absorbs?
bool absorbs_fluorescence(const Scene& scene, const FluorescentPigment& absorber) {
  for (const auto& medium : scene.fluorescence)
    for (const FluorescentPigment& emitter : medium) {
      double overlap = 0;
      for (float l = kLambdaMinUV; l < kLambdaMax; l += 1.f) overlap += emitter.emission(l) * absorber.epsilon(l);
      if (overlap > 0) return true;
    }
  return false;
}

// Does any medium scatter, any surface reflect, or any fluorescent pigment
// absorb what a fluorescent pigment emits? If none, direct excitation is exact.
std::string why_direct_is_not_exact(const Scene& scene) {
  for (size_t m = 0; m < scene.media.size(); ++m)
    if (can_scatter(scene.media[m])) return fmt::format("medium \"{}\" scatters", scene.medium_names[m]);
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const ShapeBinding& b = scene.shapes[s];
    if (b.material >= 0 && !is_interface(scene.materials[b.material]))
      return "surfaces reflect or refract excitation light";
  }
  for (const auto& medium : scene.fluorescence)
    for (const FluorescentPigment& absorber : medium)
      if (absorbs_fluorescence(scene, absorber)) return "fluorescent pigments reabsorb emitted light";
  return {};
}

// The camera's wavelength density (spectra/wavelength_sampling.h): half the eye's
// importance, which keeps every visible wavelength sampled; 30 % the lights'
// visible spectral power times the colour-matching functions (x̄ + ȳ + z̄), which
// puts lanes on a lamp's emission lines in proportion to what they add to the
// image; 20 % the fluorescent pigments' emission times the same, where re-emitted
// light lands. A scene without lights or fluorescence shares the rest.
WavelengthDistribution camera_wavelength_distribution(const Scene& scene) {
  if (scene.settings.camera_wavelengths == CameraWavelengths::visible) return WavelengthDistribution::visible();
  const auto colour = [](float lambda) {
    const XYZ c = cie_cmf(lambda);
    return c.x + c.y + c.z;
  };
  struct Source {
    const Spectrum* spectrum;
    double weight;  // multiplies spectrum(λ)
  };
  std::vector<Source> lights, pigments;
  for (const Light& light : scene.lights) {
    const Spectrum& s = emission_spectrum(light);
    const double integral = s.integral(kLambdaMin, kLambdaMax);
    const double power = light_power(light, scene.geometry, kLambdaMin, kLambdaMax);
    // power / ∫s: the light's visible power per unit of its spectrum's value.
    if (integral > 0 && power > 0 && std::isfinite(power / integral)) lights.push_back({&s, power / integral});
  }
  for (const auto& medium : scene.fluorescence)
    for (const FluorescentPigment& fp : medium) pigments.push_back({&fp.emission, 1.0});
  const auto sum_of = [colour](std::vector<Source> sources) {
    return [colour, sources = std::move(sources)](float lambda) {
      double sum = 0;
      for (const Source& s : sources) sum += s.weight * double((*s.spectrum)(lambda));
      return sum * colour(lambda);
    };
  };
  return WavelengthDistribution::mixture({{[](float lambda) { return double(visible_wavelength_pdf(lambda)); }, 0.5},
                                          {sum_of(std::move(lights)), 0.3},
                                          {sum_of(std::move(pigments)), 0.2}});
}

void setup_fluorescence(Scene& scene, const std::string& mode) {
  for (size_t m = 0; m < scene.media.size(); ++m) {
    for (FluorescentPigment& fp : scene.fluorescence[m]) {
      std::vector<double> weights;
      const bool skip = scene.settings.skip_unneeded_work;
      for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light& light = scene.lights[l];
        ExcitationSampler es(emission_spectrum(light), fp.epsilon, scene.settings.excitation_sampling);
        // Weight: the light's power times the share of its spectrum the pigment
        // can absorb, so lights dark in the excitation band are never picked.
        const double total = emission_spectrum(light).integral(kLambdaMinUV, kLambdaMax);
        const double in_band = skip ? es.total() / std::max(1e-300, total) : 1.0;
        const double w = light_power(light, scene.geometry, kLambdaMinUV, kLambdaMax) * in_band;
        if (!(w > 0.0)) continue;
        fp.lights.push_back(int(l));
        fp.excitation.push_back(std::move(es));
        weights.push_back(w);
        fp.lights_light_surfaces |= light_position(light).has_value() || std::holds_alternative<AreaLight>(light);
      }
      if (!fp.lights.empty()) fp.light_sampler = LightSampler(fp.lights, relative_weights(weights));
    }
  }
  // Reabsorption: every fluorescent pigment's emission against every pigment's
  // absorption (the emitter may sit in another medium). Always by importance:
  // render.excitation_sampling measures the lights' tables only.
  std::vector<const FluorescentPigment*> emitters;
  for (const auto& pigments : scene.fluorescence)
    for (const FluorescentPigment& fp : pigments) emitters.push_back(&fp);
  for (auto& pigments : scene.fluorescence)
    for (FluorescentPigment& fp : pigments) {
      std::vector<float> weights;
      for (const FluorescentPigment* emitter : emitters) {
        ExcitationSampler es(emitter->emission, fp.epsilon, ExcitationSampling::importance);
        const float w = emitter->quantum_yield * es.total();
        if (!(w > 0.f)) continue;
        fp.reabsorption.push_back(std::move(es));
        weights.push_back(w);
      }
      if (!weights.empty()) fp.reabsorption_choice = Distribution1D(weights);
    }
  RenderSettings& s = scene.settings;
  if (mode == "off") {
    s.fluorescence = FluorescenceMode::off;
    s.fluorescence_auto = false;
  } else if (mode == "direct" || mode == "full" || mode == "reference") {
    s.fluorescence = mode == "direct" ? FluorescenceMode::direct
                     : mode == "full" ? FluorescenceMode::full
                                      : FluorescenceMode::reference;
    s.fluorescence_auto = false;
    const std::string why = why_direct_is_not_exact(scene);
    s.fluorescence_reason = mode == "direct" && !why.empty() ? "requested; an approximation here: " + why
                                                             : "requested";
    if (mode == "reference" && (s.excitation_sampling != ExcitationSampling::importance ||
                                s.quantum_yield_mode != QuantumYieldMode::weight))
      s.fluorescence_reason +=
          "; render.excitation_sampling and render.quantum_yield_mode do not apply to it (the thesis's estimator "
          "always draws the excitation wavelength uniformly below the emitted one and uses Q as a roulette)";
  } else {
    const std::string why = why_direct_is_not_exact(scene);
    s.fluorescence = why.empty() ? FluorescenceMode::direct : FluorescenceMode::full;
    s.fluorescence_reason = why.empty() ? "auto: exact here, nothing scatters, reflects or reabsorbs"
                                        : "auto: " + why;
  }
  // Pigments nothing can excite cost nothing: no light shines in their
  // absorption band and (in full mode) no fluorescent pigment emits into it.
  // (A pigment with Q = 0 or no emission is never fluorescent: read_medium.)
  if (s.skip_unneeded_work)
    for (auto& medium : scene.fluorescence)
      std::erase_if(medium, [&](const FluorescentPigment& fp) {
        if (!fp.excitation.empty() && fp.excitation_possible()) return false;
        return s.fluorescence != FluorescenceMode::full || !absorbs_fluorescence(scene, fp);
      });
}

}  // namespace

void set_scene_key(nlohmann::json& json, std::string_view key_view, nlohmann::json value, std::string_view where) {
  const std::string key(key_view), w(where);
  nlohmann::json* node = &json;
  size_t start = 0;
  while (start <= key.size()) {
    size_t end = key.find('.', start);
    if (end == std::string::npos) end = key.size();
    std::string part = key.substr(start, end - start);
    std::optional<size_t> index;
    if (const size_t open = part.find('['); open != std::string::npos) {
      const std::string digits = part.size() > open + 2 ? part.substr(open + 1, part.size() - open - 2) : "";
      if (part.back() != ']' || digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos ||
          digits.size() > 9)
        throw InputError("command line", w, key, "malformed index in \"" + part + "\"");
      index = std::stoul(digits);
      part = part.substr(0, open);
    }
    if (part.empty()) throw InputError("command line", w, key, "empty key component");
    if (!node->is_object()) throw InputError("command line", w, key, "\"" + part + "\" is not inside an object");
    node = &(*node)[part];
    if (index) {
      if (!node->is_array() || *index >= node->size())
        throw InputError("command line", w, key, fmt::format("\"{}\" has no element {}", part, *index));
      node = &(*node)[*index];
    }
    start = end + 1;
  }
  *node = std::move(value);
}

void apply_scene_set(nlohmann::json& json, std::string_view key_equals_value) {
  const std::string set(key_equals_value);
  const size_t eq = set.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("command line", "--set", set, "expected KEY=VALUE, e.g. render.skip_unneeded_work=false");
  const std::string key = set.substr(0, eq), text = set.substr(eq + 1);
  // An array or object must be valid JSON (checked like a scene file: no
  // duplicate keys, bounded nesting); any other word that is not JSON is a string.
  nlohmann::json value;
  if (!text.empty() && (text[0] == '[' || text[0] == '{')) value = ParamReader::parse_text(text, "command line: --set " + key);
  else if (value = nlohmann::json::parse(text, nullptr, false); value.is_discarded()) value = text;
  set_scene_key(json, std::string_view(set).substr(0, eq), std::move(value), "--set");
}

Scene load_scene(const std::filesystem::path& file, const SceneOverrides& overrides) {
  return load_scene(ParamReader::parse_file(file), file, overrides);
}

Scene load_scene(const std::filesystem::path& file, const SceneOverrides& overrides, std::span<const std::string> sets) {
  nlohmann::json json = ParamReader::parse_file(file);
  for (const std::string& s : sets) apply_scene_set(json, s);
  return load_scene(json, file, overrides);
}

Scene load_scene(const nlohmann::json& json, const std::filesystem::path& file, const SceneOverrides& overrides) {
  ParamReader top(json, file, "");
  const float unit = length_unit_in_metres(top);
  std::string fluorescence_mode, transmittance;
  const RenderSettings settings = read_render_settings(top, overrides, &fluorescence_mode, &transmittance);
  Vec3 scene_eye, scene_target;
  Scene scene(read_camera(top, settings, unit, &scene_eye, &scene_target));
  scene.file = file;
  scene.settings = settings;
  scene.sensors = read_sensors(top, settings);

  // Pigments and media.
  const PigmentTable pigments = read_pigments(top);
  NameTable media;
  GridCache grids;
  for (auto& [name, m] : top.children_map("media")) {
    MediumDefinition def = read_medium(m, pigments, grids);
    media.add(name, int(scene.media.size()));
    scene.media.push_back(std::move(def.medium));
    scene.medium_names.push_back(name);
    scene.medium_scatters.push_back(can_scatter(scene.media.back()));
    scene.fluorescence.push_back(std::move(def.fluorescent));
  }

  for (const auto& [key, grid] : grids)
    if (!grid->metadata().converted_from.empty())
      scene.notes.push_back(fmt::format("{}: grid {} holds {} values: converted to float on load",
                                        grid->metadata().file, grid->metadata().name, grid->metadata().converted_from));

  NameTable materials;
  for (auto& [name, m] : top.children_map("materials")) {
    materials.add(name, int(scene.materials.size()));
    scene.materials.push_back(read_material(m));
  }

  // Shapes (and their area lights).
  std::vector<bool> medium_bounded(scene.media.size(), false);
  for (ParamReader& sh : top.children_array("shapes")) {
    const std::string type = sh.get_enum("type", "", {"quad", "box", "disk", "sphere", "mesh"});
    const Transform world_from_object = read_transform(sh, unit);
    ShapeBinding b;
    int id;
    bool closed;
    if (type == "sphere") {
      if (!world_from_object.is_identity()) sh.fail("transform", "spheres take \"center\" and \"radius\" only");
      id = scene.geometry.add_sphere(sh.get_vec3("center", {}) * unit, sh.require_float("radius", 1e-30f) * unit);
      closed = true;
    } else {
      TriangleMesh mesh = read_shape_mesh(sh, type, unit);
      closed = is_closed(mesh);
      id = scene.geometry.add_mesh(std::move(mesh), world_from_object);
    }
    if (sh.has("material")) b.material = materials.find(sh, "material", "material");
    if (sh.has("inside")) b.medium_inside = media.find(sh, "inside", "medium");
    if (sh.has("outside")) b.medium_outside = media.find(sh, "outside", "medium");
    if (b.medium_inside >= 0) {
      if (!closed) sh.fail("inside", "the shape is not closed, so it has no inside to fill");
      medium_bounded[b.medium_inside] = true;
    }
    if (auto e = sh.optional_child("emission")) {
      AreaLight light{id, read_spectrum(*e, "spectrum", named_spectrum("D65")), e->get_float("scale", 1.f, 0.f, 1e20f),
                      e->get_bool("two_sided", false)};
      e->finish();
      b.area_light = int(scene.lights.size());
      scene.lights.push_back(light);
    }
    if (b.material < 0 && b.area_light < 0 && b.medium_inside < 0 && b.medium_outside < 0)
      sh.fail("material", "a shape needs a material, an emission or a medium");
    sh.finish();
    if (int(scene.shapes.size()) != id) throw std::logic_error("shape ids must be dense");
    scene.shapes.push_back(b);
  }
  // A grid in the wrong length unit is 100 or 1000 times too small or too big and
  // renders as nothing or as a fog over everything: compare it with the rest of the scene.
  Bounds3 others = scene.geometry.bounds();
  others.extend(scene_eye);
  others.extend(scene_target);
  const float scene_size = max_component(others.hi - others.lo);
  for (size_t m = 0; m < scene.media.size(); ++m) {
    const std::optional<Bounds3> box = medium_bounds(scene.media[m]);
    if (!box || box->empty() || !(scene_size > 0.f)) continue;
    const float grid_size = max_component(box->hi - box->lo);
    if (grid_size < scene_size / kGridScaleWarning || grid_size > scene_size * kGridScaleWarning)
      scene.warnings.push_back(fmt::format(
          "{}: media.{}: the grid is {:.3g} m across, the camera and shapes span {:.3g} m: check the grid's "
          "length unit (its \"length_unit\" metadata, metres by default, or the grid's \"length_unit\" key)",
          file.string(), scene.medium_names[m], grid_size, scene_size));
  }
  // A grid medium no shape bounds fills its grid's world box, behind an invisible interface.
  for (size_t m = 0; m < scene.media.size(); ++m) {
    if (medium_bounded[m]) continue;
    const std::optional<Bounds3> box = medium_bounds(scene.media[m]);
    if (!box) continue;
    const int id = scene.geometry.add_box(*box);
    ShapeBinding b;
    b.medium_inside = int(m);
    scene.shapes.push_back(b);
    if (int(scene.shapes.size()) != id + 1) throw std::logic_error("shape ids must be dense");
  }
  if (top.has("camera_medium")) scene.camera_medium = media.find(top, "camera_medium", "medium");

  for (ParamReader& l : top.children_array("lights")) scene.lights.push_back(read_light(l, unit));
  top.finish();

  scene.geometry.commit();
  const Bounds3 bounds = scene.geometry.bounds();
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    preprocess(scene.lights[l], bounds);
    if (std::holds_alternative<EnvironmentLight>(scene.lights[l])) scene.infinite_lights.push_back(int(l));
  }
  std::vector<double> power;
  // Camera paths carry visible wavelengths only: UV power they never see must not
  // draw their light samples (a UVB lamp tripled the noise of visible lighting).
  // A uniform environment is not light-sampled on camera paths (as pbrt-v4's volpath): at
  // a diffuse surface or an isotropic phase vertex the scattering sample already draws its
  // directions as well as a uniform sphere would, so its NEE sample bought little and took
  // half the samples from lights only NEE can reach (cloud benchmark: -36 % MSE, -9 % time).
  // Escaping paths then carry its radiance with MIS weight 1. Excitation keeps sampling it.
  for (const Light& light : scene.lights)
    power.push_back(std::holds_alternative<EnvironmentLight>(light)
                        ? 0.0
                        : light_power(light, scene.geometry, kLambdaMin, kLambdaMax));
  scene.light_sampler = LightSampler(relative_weights(power));
  setup_fluorescence(scene, fluorescence_mode);
  // The photon grid is laid over the shapes that hold a fluorescent medium: one no
  // shape encloses (the room's air) would get no grid and silently no fluorescence.
  if (scene.settings.excitation_estimate == ExcitationEstimate::photons)
    for (size_t m = 0; m < scene.media.size(); ++m) {
      if (scene.fluorescence[m].empty()) continue;
      const bool enclosed = std::any_of(scene.shapes.begin(), scene.shapes.end(),
                                        [&](const ShapeBinding& b) { return b.medium_inside == int(m); });
      if (!enclosed)
        throw InputError(file.string(), "render.excitation_estimate", "photons",
                         fmt::format("medium \"{}\" fluoresces but no shape encloses it, and the photon grid is laid "
                                     "over the shapes that do: give it a shape or use \"rays\"",
                                     scene.medium_names[m]));
    }
  // The photon cells weight the excitation by concentration, but a cell's one
  // exponential profile follows the fall of the light through a pigment layer much
  // thinner than the cell (a curved leaf blade, the camera seeing its lit face) only
  // as far as the photons' noise and the layer's curvature in the cell let it.
  if (scene.settings.excitation_estimate == ExcitationEstimate::photons)
    for (size_t m = 0; m < scene.media.size(); ++m)
      for (const FluorescentPigment& fp : scene.fluorescence[m])
        if (scene.media[m].pigment_in_grid(fp.pigment)) {
          scene.warnings.push_back(fmt::format(
              "{}: render.excitation_estimate \"photons\": medium \"{}\" holds its pigment in a grid; a pigment "
              "layer much thinner than a photon cell that absorbs strongly (a leaf's blade) comes out low, less so with "
              "more photons and finer cells (against \"rays\": leaf_D65.json -7 %, leaf_UVB.json -8 % at the "
              "defaults and -5 % with render.excitation_grid_cells 64 and render.excitation_photons 4194304; the "
              "spills -1 % and -2 %); check against \"rays\"",
              file.string(), scene.medium_names[m]));
          break;
        }
  scene.camera_wavelengths = camera_wavelength_distribution(scene);
  scene.resolve_at_load();
  return scene;
}

}  // namespace chlorovdb
