#include "analysis/pbrt_export.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "core/error.h"
#include "geometry/mesh.h"
#include "lights/light.h"
#include "media/solvent.h"
#include "scene/medium_param.h"
#include "scene/param_reader.h"
#include "spectra/color.h"

namespace chlorovdb {

namespace {

std::string num(double v) { return fmt::format("{:.7g}", v); }
// Angles come back from stored cosines: 5 digits drop the float noise (25.00001 -> 25).
std::string angle(double degrees) { return fmt::format("{:.5g}", degrees); }
std::string vec(const Vec3& v) { return fmt::format("{} {} {}", num(v.x), num(v.y), num(v.z)); }

// "[l v l v ...]" in pbrt-v4's spectrum syntax over its range 360-830 nm: the
// knots of a table (exact: both renderers interpolate linearly and are zero
// outside the table), two points for a constant, 1 nm steps otherwise.
template <class F>
std::string sampled_pairs(F&& f) {
  std::vector<double> v;
  for (int l = int(kLambdaMin); l <= int(kLambdaMax); ++l) v.push_back(f(float(l)));
  if (std::all_of(v.begin(), v.end(), [&](double x) { return x == v.front(); }))  // flat: two points say it
    return fmt::format("[{} {} {} {}]", int(kLambdaMin), num(v.front()), int(kLambdaMax), num(v.front()));
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += fmt::format("{}{} {}", i ? " " : "", int(kLambdaMin) + int(i), num(v[i]));
  return s + "]";
}

std::string spectrum_pairs(const Spectrum& spectrum, double scale = 1.0) {
  const auto& rep = spectrum.representation();
  if (std::holds_alternative<Spectrum::Constant>(rep)) {
    const double v = spectrum(500.f) * scale;
    return fmt::format("[{} {} {} {}]", int(kLambdaMin), num(v), int(kLambdaMax), num(v));
  }
  if (const auto* t = std::get_if<Spectrum::Tabulated>(&rep)) {
    std::vector<std::pair<float, double>> points;
    if (t->lambda.front() < kLambdaMin && t->lambda.back() > kLambdaMin) points.emplace_back(kLambdaMin, spectrum(kLambdaMin) * scale);
    for (float l : t->lambda)
      if (l >= kLambdaMin && l <= kLambdaMax) points.emplace_back(l, spectrum(l) * scale);
    if (t->lambda.back() > kLambdaMax && t->lambda.front() < kLambdaMax) points.emplace_back(kLambdaMax, spectrum(kLambdaMax) * scale);
    if (points.size() < 2) return fmt::format("[{} 0 {} 0]", int(kLambdaMin), int(kLambdaMax));
    std::string s = "[";
    for (size_t i = 0; i < points.size(); ++i) s += fmt::format("{}{} {}", i ? " " : "", num(points[i].first), num(points[i].second));
    return s + "]";
  }
  return sampled_pairs([&](float l) { return spectrum(l) * scale; });
}

float unit_in_metres(const std::string& unit) {
  if (unit == "cm") return 1e-2f;
  if (unit == "mm") return 1e-3f;
  if (unit == "um") return 1e-6f;
  return 1.f;
}

// As scene_loader.cpp reads them (scale -> rotate -> translate; positions in the file's unit).
Transform shape_transform(ParamReader& sh, float unit) {
  auto t = sh.optional_child("transform");
  if (!t) return {};
  Transform result;
  if (t->has("scale")) {
    if (t->raw("scale").is_number()) result = Transform::scale(Vec3(t->require_float("scale")));
    else result = Transform::scale(t->require_vec3("scale"));
  }
  if (t->has("rotate")) {
    const auto r = t->get_floats("rotate", {}, 4);
    result = Transform::rotate(r[0], {r[1], r[2], r[3]}) * result;
  }
  if (t->has("translate")) result = Transform::translate(t->require_vec3("translate") * unit) * result;
  return result;
}

TriangleMesh shape_mesh(ParamReader& sh, const std::string& type, float unit) {
  if (type == "quad")
    return make_quad(sh.require_vec3("corner") * unit, sh.require_vec3("edge_u") * unit, sh.require_vec3("edge_v") * unit);
  if (type == "box") {
    Bounds3 b;
    b.lo = sh.require_vec3("min") * unit;
    b.hi = sh.require_vec3("max") * unit;
    return make_box(b);
  }
  if (type == "disk")
    return make_disk(sh.get_vec3("center", {}) * unit, sh.get_vec3("normal", {0, 1, 0}), sh.require_float("radius") * unit, 64);
  TriangleMesh mesh = load_mesh(sh.require_path("file"));
  if (unit != 1.f) mesh = transform_mesh(std::move(mesh), Transform::scale(Vec3(unit)));
  return mesh;
}

std::string trianglemesh(const TriangleMesh& m) {
  std::string s = "Shape \"trianglemesh\"\n    \"point3 P\" [";
  for (size_t i = 0; i < m.positions.size(); ++i) {
    if (i) s += ' ';
    s += vec(m.positions[i]);
  }
  s += "]\n    \"integer indices\" [";
  for (size_t i = 0; i < m.indices.size(); ++i) s += fmt::format("{}{}", i ? " " : "", m.indices[i]);
  s += "]";
  if (!m.normals.empty()) {
    s += "\n    \"normal N\" [";
    for (size_t i = 0; i < m.normals.size(); ++i) {
      if (i) s += ' ';
      s += vec(m.normals[i]);
    }
    s += "]";
  }
  if (!m.uvs.empty()) {
    s += "\n    \"point2 uv\" [";
    for (size_t i = 0; i < m.uvs.size(); ++i) s += fmt::format("{}{} {}", i ? " " : "", num(m.uvs[i].x), num(m.uvs[i].y));
    s += "]";
  }
  return s + "\n";
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// pbrt-v4 divides each light's spectrum by its photometric value: its "scale" is our scale times the luminance.
std::optional<double> pbrt_light_scale(const Spectrum& s, float scale) {
  const double Y = luminance(s);
  if (!(Y > 0)) return std::nullopt;
  return double(scale) * Y;
}

struct Writer {
  const Scene& scene;
  const std::filesystem::path& file;
  const PbrtExportOptions& options;
  PbrtExport result;
  std::string& out = result.text;

  void warn(const std::string& w) {
    result.warnings.push_back(w);
    out += "# NOTE: " + w + "\n";
  }
  [[noreturn]] void fail(const std::string& key, const std::string& problem) { throw InputError(file.string(), key, "", problem); }

  void camera() {
    const RenderSettings& s = scene.settings;
    if (scene.camera_medium >= 0) out += fmt::format("MediumInterface \"\" {}\n", quoted(scene.medium_names[scene.camera_medium]));
    const Camera::Projection& projection = scene.camera.projection();
    const Transform& world_from_camera = std::visit([](const auto& p) -> const Transform& { return p.world_from_camera; }, projection);
    const auto& m = world_from_camera.matrix();
    const Vec3 eye{m[0][3], m[1][3], m[2][3]}, forward{m[0][2], m[1][2], m[2][2]}, up{m[0][1], m[1][1], m[2][1]};
    out += "# pbrt-v4 is left-handed: mirror camera x so the image is not flipped left-right.\n";
    out += "Scale -1 1 1\n";
    out += fmt::format("LookAt {}\n       {}\n       {}\n", vec(eye), vec(eye + forward), vec(up));
    if (const auto* p = std::get_if<PerspectiveCamera>(&projection)) {
      out += fmt::format("Camera \"perspective\" \"float fov\" [{}]", num(p->fov_degrees));
      if (p->lens_radius > 0)
        out += fmt::format(" \"float lensradius\" [{}] \"float focaldistance\" [{}]", num(p->lens_radius), num(p->focus_distance));
      out += "\n";
    } else {
      const auto& o = std::get<OrthographicCamera>(projection);
      const double hh = o.screen_height / 2, hw = hh * s.width / s.height;
      out += fmt::format("Camera \"orthographic\" \"float screenwindow\" [{} {} {} {}]\n", num(-hw), num(hw), num(-hh), num(hh));
    }
    out += fmt::format("Film \"rgb\" \"integer xresolution\" [{}] \"integer yresolution\" [{}] \"string filename\" [{}]\n",
                       s.width, s.height, quoted(options.film_filename));
    if (s.color_space == ColorSpace::ACEScg)
      warn("the scene writes ACEScg; pbrt-v4's film writes linear sRGB here (convert before comparing)");
    out += "PixelFilter \"box\"  # radius 0.5: one pixel, as chlorovdb's film\n";
    out += fmt::format("Sampler \"independent\" \"integer pixelsamples\" [{}]\n", options.spp > 0 ? options.spp : s.spp);
    out += fmt::format("Integrator \"volpath\" \"integer maxdepth\" [{}]\n", s.max_depth);
    out += fmt::format("# chlorovdb carries {} wavelengths per path, pbrt-v4 4 (NSpectrumSamples): same expectation.\n\n",
                       s.wavelengths);
  }

  void medium(size_t index) {
    const Medium& medium = scene.media[index];
    const MediumDesc& d = medium.desc();
    const std::string& name = scene.medium_names[index];
    out += fmt::format("# medium \"{}\"\n", name);
    auto rayleigh = [&](float l) {
      return d.solvent.rayleigh ? water_rayleigh_sigma_s(l, d.solvent.eta(l), d.solvent.temperature_K) : 0.f;
    };
    const bool particles = d.particle_sigma_s.grid || d.particle_sigma_s.value > 0.f;
    float g = 0.f;
    if (particles) {
      if (const auto* hg = std::get_if<HenyeyGreenstein>(&d.particle_phase)) g = hg->g;
    }
    if (d.solvent.rayleigh)
      out += "# molecular (Rayleigh) scattering exported with HG g = 0: pbrt-v4 has no Rayleigh phase function\n";

    if (medium.homogeneous()) {
      auto sigma_a = [&](float l) {
        double v = d.solvent.absorption(l);
        for (const PigmentInMedium& p : d.pigments) v += kAbsorptionPerMolarExtinction * double(p.pigment.epsilon(l)) * p.concentration.value;
        return v;
      };
      auto sigma_s = [&](float l) { return double(rayleigh(l)) + d.particle_sigma_s.value; };
      out += fmt::format("MakeNamedMedium {} \"string type\" \"homogeneous\"\n", quoted(name));
      out += "    \"spectrum sigma_a\" " + sampled_pairs(sigma_a) + "\n";
      out += "    \"spectrum sigma_s\" " + sampled_pairs(sigma_s) + "\n";
      out += fmt::format("    \"float scale\" [1] \"float g\" [{}]\n\n", num(g));
      return;
    }

    // Grid medium: pbrt-v4's uniformgrid scales sigma_a and sigma_s by ONE density grid.
    const VoxelGrid* grid = nullptr;
    auto use = [&](const std::shared_ptr<const VoxelGrid>& g, const std::string& what) {
      if (!g) return;
      if (grid && grid != g.get())
        fail("media." + name, "pbrt-v4's uniformgrid medium takes one density grid; " + what + " uses a second grid");
      grid = g.get();
    };
    for (const PigmentInMedium& p : d.pigments) use(p.concentration.grid, "pigment \"" + p.pigment.name + "\"");
    use(d.particle_sigma_s.grid, "particle scattering");
    // The stored box is whole 8^3 bricks; dump only the voxels that differ from
    // the background (pbrt-v4's lookups outside the dumped box return 0, as
    // ours return the background, checked to be 0 below).
    Coord lo = grid->index_hi(), hi = grid->index_lo();
    for (int z = grid->index_lo()[2]; z <= grid->index_hi()[2]; ++z)
      for (int y = grid->index_lo()[1]; y <= grid->index_hi()[1]; ++y)
        for (int x = grid->index_lo()[0]; x <= grid->index_hi()[0]; ++x)
          if (grid->voxel(x, y, z) != grid->background()) {
            lo = {std::min(lo[0], x), std::min(lo[1], y), std::min(lo[2], z)};
            hi = {std::max(hi[0], x), std::max(hi[1], y), std::max(hi[2], z)};
          }
    if (lo[0] > hi[0]) lo = hi = grid->index_lo();  // all background: one voxel
    const int64_t nx = hi[0] - lo[0] + 1, ny = hi[1] - lo[1] + 1, nz = hi[2] - lo[2] + 1;
    if (nx * ny * nz > options.max_grid_voxels)
      fail("media." + name, fmt::format("grid of {}x{}x{} voxels is over the export limit of {} voxels", nx, ny, nz,
                                        options.max_grid_voxels));
    // Coefficients per unit grid value, and what cannot ride on the grid.
    auto sigma_a_per_value = [&](float l) {
      double v = 0;
      for (const PigmentInMedium& p : d.pigments)
        if (p.concentration.grid) v += kAbsorptionPerMolarExtinction * double(p.pigment.epsilon(l)) * p.concentration.scale;
      return v;
    };
    auto sigma_s_per_value = [&](float l) { return d.particle_sigma_s.grid ? double(d.particle_sigma_s.scale) : 0.0; };
    double dropped_a = 0, dropped_s = 0;
    for (float l = kLambdaMin; l <= kLambdaMax; l += 1.f) {
      double a = d.solvent.absorption(l);
      for (const PigmentInMedium& p : d.pigments)
        if (!p.concentration.grid) a += kAbsorptionPerMolarExtinction * double(p.pigment.epsilon(l)) * p.concentration.value;
      dropped_a = std::max(dropped_a, a);
      dropped_s = std::max(dropped_s, double(rayleigh(l)) + (d.particle_sigma_s.grid ? 0.0 : d.particle_sigma_s.value));
    }
    if (dropped_a > 0 || dropped_s > 0)
      warn(fmt::format("medium \"{}\": pbrt-v4's uniformgrid scales every coefficient by the one grid, so the uniform "
                       "part (solvent, constant pigments, molecular scattering: up to sigma_a {:.3g} /m, sigma_s {:.3g} /m "
                       "over 360-830 nm) is left out",
                       name, dropped_a, dropped_s));
    if (grid->background() != 0.f)
      warn(fmt::format("medium \"{}\": grid background {} is 0 outside the dumped box in pbrt-v4", name, grid->background()));
    if (d.interpolation == Interpolation::nearest) warn(fmt::format("medium \"{}\": nearest lookups become trilinear in pbrt-v4", name));
    // Index space -> world: pbrt's [0,1]^3 grid space puts voxel i's centre at
    // (i + 1/2) / n, so the box p0..p1 spans the voxel cells [lo - 1/2, hi + 1/2].
    const auto& m = grid->world_from_index().matrix();
    out += "AttributeBegin\n  ConcatTransform [";
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) out += fmt::format("{}{}", c || r ? " " : "", num(m[r][c]));
    out += "]\n";
    out += fmt::format("  MakeNamedMedium {} \"string type\" \"uniformgrid\"\n", quoted(name));
    out += fmt::format("    \"integer nx\" [{}] \"integer ny\" [{}] \"integer nz\" [{}]\n", nx, ny, nz);
    out += fmt::format("    \"point3 p0\" [{} {} {}] \"point3 p1\" [{} {} {}]\n", lo[0] - 0.5, lo[1] - 0.5, lo[2] - 0.5,
                       hi[0] + 0.5, hi[1] + 0.5, hi[2] + 0.5);
    out += "    \"spectrum sigma_a\" " + sampled_pairs(sigma_a_per_value) + "\n";
    out += "    \"spectrum sigma_s\" " + sampled_pairs(sigma_s_per_value) + "\n";
    out += fmt::format("    \"float scale\" [1] \"float g\" [{}]\n    \"float density\" [", num(g));
    int64_t count = 0;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) out += fmt::format("{}{}", count++ % 16 ? " " : "\n      ", num(grid->voxel(x, y, z)));
    out += "]\nAttributeEnd\n\n";
  }

  void material(const std::string& name, const Material& m) {
    if (const auto* d = std::get_if<Diffuse>(&m)) {
      out += fmt::format("MakeNamedMaterial {} \"string type\" \"diffuse\" \"spectrum reflectance\" {}\n", quoted(name),
                         spectrum_pairs(d->albedo));
    } else if (const auto* g = std::get_if<Dielectric>(&m)) {
      if (const float* eta = std::get_if<float>(&g->ior))
        out += fmt::format("MakeNamedMaterial {} \"string type\" \"dielectric\" \"float eta\" [{}]\n", quoted(name), num(*eta));
      else
        out += fmt::format("MakeNamedMaterial {} \"string type\" \"dielectric\" \"spectrum eta\" {}\n", quoted(name),
                           sampled_pairs([&](float l) { return ior_at(*g, l); }));
    } else {
      out += fmt::format("MakeNamedMaterial {} \"string type\" \"interface\"\n", quoted(name));
    }
  }

  void light(size_t index) {
    const Light& light = scene.lights[index];
    if (std::holds_alternative<AreaLight>(light)) return;  // with its shape
    const Spectrum& spectrum = emission_spectrum(light);
    const auto scale = pbrt_light_scale(spectrum, light_scale(light));
    if (!scale) {
      warn(fmt::format("light {} emits nothing between 360 and 830 nm (pbrt-v4 normalises lights by luminance): left out", index));
      return;
    }
    if (const auto* p = std::get_if<PointLight>(&light)) {
      out += fmt::format("LightSource \"point\" \"point3 from\" [{}] \"float scale\" [{}]\n    \"spectrum I\" {}\n",
                         vec(p->position), num(*scale), spectrum_pairs(spectrum));
    } else if (const auto* s = std::get_if<SpotLight>(&light)) {
      const double cone = std::acos(std::clamp(s->cos_falloff_end, -1.f, 1.f)) * 180 / M_PI;
      const double start = std::acos(std::clamp(s->cos_falloff_start, -1.f, 1.f)) * 180 / M_PI;
      out += fmt::format("LightSource \"spot\" \"point3 from\" [{}] \"point3 to\" [{}]\n"
                         "    \"float coneangle\" [{}] \"float conedeltaangle\" [{}] \"float scale\" [{}]\n    \"spectrum I\" {}\n",
                         vec(s->position), vec(s->position + s->direction), angle(cone), angle(cone - start), num(*scale),
                         spectrum_pairs(spectrum));
    } else if (const auto* d = std::get_if<DistantLight>(&light)) {
      // pbrt: light travels from "from" toward "to".
      out += fmt::format("LightSource \"distant\" \"point3 from\" [0 0 0] \"point3 to\" [{}] \"float scale\" [{}]\n    \"spectrum L\" {}\n",
                         vec(d->direction), num(*scale), spectrum_pairs(spectrum));
    } else {
      out += fmt::format("LightSource \"infinite\" \"float scale\" [{}]\n    \"spectrum L\" {}\n", num(*scale),
                         spectrum_pairs(spectrum));
    }
  }

  void shape_attributes(const ShapeBinding& b, const std::string& material_name) {
    if (b.material >= 0 && !material_name.empty()) out += fmt::format("  NamedMaterial {}\n", quoted(material_name));
    else out += "  Material \"interface\"\n";
    const std::string inside = b.medium_inside >= 0 ? scene.medium_names[b.medium_inside] : "";
    const std::string outside = b.medium_outside >= 0 ? scene.medium_names[b.medium_outside] : "";
    if (!inside.empty() || !outside.empty()) out += fmt::format("  MediumInterface {} {}\n", quoted(inside), quoted(outside));
    if (b.area_light >= 0) {
      const auto& a = std::get<AreaLight>(scene.lights[b.area_light]);
      const auto scale = pbrt_light_scale(a.Le, a.scale);
      if (scale)
        out += fmt::format("  AreaLightSource \"diffuse\" \"float scale\" [{}] \"bool twosided\" [{}]\n    \"spectrum L\" {}\n",
                           num(*scale), a.two_sided ? "true" : "false", spectrum_pairs(a.Le));
      else
        warn(fmt::format("area light {} emits nothing between 360 and 830 nm: exported without emission", b.area_light));
    }
  }
};

}  // namespace

PbrtExport export_pbrt(const Scene& scene, const std::filesystem::path& file, const PbrtExportOptions& options) {
  for (size_t m = 0; m < scene.media.size(); ++m)
    for (const PigmentInMedium& p : scene.media[m].desc().pigments)
      if (p.pigment.quantum_yield > 0.f && !options.ignore_fluorescence)
        throw InputError(file.string(), "media." + scene.medium_names[m], p.pigment.name,
                         "fluoresces (quantum_yield > 0), which pbrt-v4 cannot render; use --ignore-fluorescence to "
                         "export it as an absorber and compare with `chlorovdb render --fluorescence off`");
  Writer w{scene, file, options, {}};
  std::string& out = w.out;
  out += fmt::format("# pbrt-v4 scene exported by chlorovdb export-pbrt from {}\n", file.string());
  out += "# Lengths in metres, wavelengths in nm, coefficients in 1/m. Spectra are [lambda value ...] pairs.\n";
  if (options.ignore_fluorescence && scene.has_fluorescence())
    w.warn("fluorescence ignored: pigments exported as absorbers only (compare with render --fluorescence off)");
  out += "\n";
  w.camera();
  out += "\nWorldBegin\n\n";
  for (size_t m = 0; m < scene.media.size(); ++m) w.medium(m);

  const nlohmann::json json = ParamReader::parse_file(file);
  ParamReader top(json, file, "");
  const float unit = unit_in_metres(top.get_string("length_unit", "m"));
  std::vector<ParamReader> shapes = top.children_array("shapes");

  // Materials by the names the shapes use (a material is written once).
  std::set<std::string> written;
  for (size_t i = 0; i < shapes.size() && i < scene.shapes.size(); ++i) {
    const ShapeBinding& b = scene.shapes[i];
    if (b.material < 0) continue;
    const std::string name = shapes[i].get_string("material", "");
    if (written.insert(name).second) w.material(name, scene.materials[b.material]);
  }
  out += "\n";
  for (size_t l = 0; l < scene.lights.size(); ++l) w.light(l);
  out += "\n";

  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const ShapeBinding& b = scene.shapes[i];
    out += "AttributeBegin\n";
    if (i < shapes.size()) {
      ParamReader& sh = shapes[i];
      const std::string type = sh.get_string("type", "");
      w.shape_attributes(b, b.material >= 0 ? sh.get_string("material", "") : "");
      if (type == "sphere") {
        out += fmt::format("  Translate {}\n  Shape \"sphere\" \"float radius\" [{}]\n", vec(sh.get_vec3("center", {}) * unit),
                           num(sh.require_float("radius") * unit));
      } else {
        TriangleMesh mesh = shape_mesh(sh, type, unit);
        const Transform world_from_object = shape_transform(sh, unit);
        if (!world_from_object.is_identity()) mesh = transform_mesh(std::move(mesh), world_from_object);
        drop_degenerate_triangles(mesh);
        out += "  " + trianglemesh(mesh);
      }
    } else {
      // A grid medium no shape bounds fills its grid's world box (as the loader does).
      const std::optional<Bounds3> box = b.medium_inside >= 0 ? medium_bounds(scene.media[b.medium_inside]) : std::nullopt;
      if (!box) throw std::logic_error("export_pbrt: shapes of the scene do not match its file");
      out += fmt::format("  # the box of grid medium \"{}\"\n", scene.medium_names[b.medium_inside]);
      w.shape_attributes(b, "");
      out += "  " + trianglemesh(make_box(*box));
    }
    out += "AttributeEnd\n";
  }
  return std::move(w.result);
}

}  // namespace chlorovdb
