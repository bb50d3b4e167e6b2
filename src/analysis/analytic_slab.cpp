#include "analysis/analytic_slab.h"

#include <cmath>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include "core/error.h"
#include "grids/vdb_file.h"
#include "lights/light.h"

namespace chlorovdb {

namespace {

constexpr double kMicromolarAbsorption = 100.0 * 2.302585092994046 * 1e-6;  // 1/m per (L/mol/cm · µM)
constexpr double kHalfWidth = 0.05;  // m: the slab's lateral half extent (the view is 1 cm wide)

constexpr double kGlassGap = 0.001;  // m between the plate and the lit face

// Fresnel reflectance of s- and p-polarised light from index 1 into n at incidence theta.
std::pair<double, double> fresnel_sp(double n, double theta) {
  const double ci = std::cos(theta), st = std::sin(theta) / n, ct = std::sqrt(1 - st * st);
  const double rs = (ci - n * ct) / (ci + n * ct), rp = (n * ci - ct) / (n * ci + ct);
  return {rs * rs, rp * rp};
}

}  // namespace

double plate_transmission(double n, double theta) {
  const auto [Rs, Rp] = fresnel_sp(n, theta);
  const double R = 0.5 * (Rs + Rp);
  return (1 - R) * (1 - R) / (1 - R * R);
}

namespace {

double incidence_rad(const SlabCase& s) { return s.incidence_deg * M_PI / 180.0; }

double concentration_at_depth(const SlabCase& s, double depth) { return s.c_lit + (s.c_far - s.c_lit) * depth / s.D; }

// int_0^D mu_a(s) e^{-tau'(s)} e^{-zeta d(s)} ds for a flat extinction eps (composite Simpson).
double depth_integral(const SlabCase& s, double eps) {
  const int n = 4000;  // even
  const double h = s.D / n;
  const double k = kMicromolarAbsorption * eps;
  const double sec = 1.0 / std::cos(incidence_rad(s));  // the beam's path per unit depth
  // Behind a glass plate the camera also sees the lit-side emission reflected by the plate.
  double R_eff = 0;
  if (s.glass_ior > 0) {
    const double R = std::pow((s.glass_ior - 1) / (s.glass_ior + 1), 2);
    R_eff = 2 * R / (1 + R);
  }
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double depth = i * h;
    const double tau_excitation =
        sec * (s.zeta * depth + k * (s.c_lit * depth + (s.c_far - s.c_lit) * depth * depth / (2 * s.D)));
    const double tau_emission = s.zeta * (s.reflection_side ? depth : s.D - depth);
    const double seen = std::exp(-tau_emission) + R_eff * std::exp(-s.zeta * (s.D + depth));
    const double f = k * concentration_at_depth(s, depth) * std::exp(-tau_excitation) * seen;
    sum += f * (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2));
  }
  return sum * h / 3;
}

const Pigment& slab_pigment(const Scene& scene) {
  if (scene.media.empty() || scene.media[0].desc().pigments.empty())
    throw std::invalid_argument("not a slab scene: no pigment in the first medium");
  return scene.media[0].desc().pigments[0].pigment;
}

// A = int dl' l' E(l') G(eps(l')), E including the light's scale.
double excitation_integral(const SlabCase& s, const Scene& scene) {
  const Pigment& p = slab_pigment(scene);
  const Spectrum& E = emission_spectrum(scene.lights.at(0));
  double E_scale = light_scale(scene.lights.at(0));
  if (s.glass_ior > 0) E_scale *= plate_transmission(s.glass_ior, incidence_rad(s));
  std::map<float, double> G;  // by extinction value: flat inside the band, so a handful of entries
  const double step = 0.01, lo = s.eps_lo - 0.5, hi = s.eps_hi + 0.5;
  const int n = int(std::lround((hi - lo) / step));
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double lp = lo + i * step;
    const float eps = p.epsilon(float(lp));
    if (eps <= 0.f) continue;
    auto it = G.find(eps);
    if (it == G.end()) it = G.emplace(eps, depth_integral(s, eps)).first;
    sum += (i == 0 || i == n ? 0.5 : 1.0) * lp * E(float(lp)) * E_scale * it->second;
  }
  return sum * step;
}

std::string spectrum_or_number(double v) { return fmt::format("{}", v); }

}  // namespace

std::vector<std::string> analytic_case_names() {
  return {"slab", "slab_transmission", "slab_linear", "slab_glass_wall", "slab_glass_wall_oblique"};
}

SlabCase analytic_case(std::string_view name) {
  SlabCase s;
  s.name = std::string(name);
  if (name == "slab") return s;
  if (name == "slab_transmission") {
    s.reflection_side = false;
    return s;
  }
  if (name == "slab_linear") {
    // Dense at the lit face, dilute at the far one: the majorant grid's cells
    // bound a range of concentrations, so ratio, residual ratio and delta
    // tracking all do real work.
    s.grid = true;
    s.c_lit = 40;
    s.c_far = 5;
    return s;
  }
  if (name == "slab_glass_wall" || name == "slab_glass_wall_oblique") {
    s.reflection_side = false;
    s.glass_ior = 1.5;
    if (name == "slab_glass_wall_oblique") s.incidence_deg = 60;
    return s;
  }
  std::string names;
  for (const std::string& n : analytic_case_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError("command line", "--analytic", name, "unknown analytic case (known: " + names + ")");
}

std::filesystem::path write_slab_scene(const SlabCase& s, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  if (s.c_lit != s.c_far && !s.grid) throw std::invalid_argument("a slab with a concentration gradient needs grid = true");
  if (s.glass_ior > 0 && s.reflection_side)
    throw std::invalid_argument("a slab behind glass is observed from its far side only");
  if (!(s.incidence_deg >= 0 && s.incidence_deg < 89))
    throw std::invalid_argument("slab incidence angle must lie in [0, 89) degrees");
  std::string glass_material, glass_shape;
  if (s.glass_ior > 0) {
    glass_material = fmt::format(R"(, "glass": {{"type": "dielectric", "ior": {}}})", s.glass_ior);
    glass_shape = fmt::format(R"(, {{"type": "box", "min": [-{w}, -{w}, {z0}], "max": [{w}, {w}, {z1}], "material": "glass"}})",
                              fmt::arg("w", kHalfWidth), fmt::arg("z0", s.D + kGlassGap),
                              fmt::arg("z1", s.D + kGlassGap + s.glass_thickness));
  }
  const double theta = incidence_rad(s);
  std::string pigment_in_medium;
  if (s.grid) {
    // Voxel centres every D/8 in z from -D/8 to D + D/8 and 4 x 4 laterally,
    // one voxel beyond the box on every side, so no lookup inside the slab
    // reaches the background and the field is exactly linear there.
    const int nz = 11;
    const double dz = s.D / 8, dxy = 0.04;
    DenseGrid g({4, 4, nz});
    g.world_from_index = Transform::translate(Vec3(float(-1.5 * dxy), float(-1.5 * dxy), float(-dz))) *
                         Transform::scale(Vec3(float(dxy), float(dxy), float(dz)));
    g.metadata.name = "concentration";
    g.metadata.unit = "uM";
    g.metadata.provenance = "chlorovdb analysis: linear slab (" + s.name + ")";
    for (int k = 0; k < nz; ++k) {
      const double z = -dz + k * dz;
      const float c = float(concentration_at_depth(s, s.D - z));
      if (c < 0.f) throw std::invalid_argument("slab concentration profile goes negative next to the slab");
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) g.at(i, j, k) = c;
    }
    write_concentration_grid(dir / (s.name + ".vdb"), g);
    pigment_in_medium = fmt::format(R"({{"pigment": "dye", "grid": {{"file": "{}.vdb", "name": "concentration", "unit": "uM"}}}})", s.name);
  } else {
    pigment_in_medium = fmt::format(R"({{"pigment": "dye", "concentration": {}, "unit": "uM"}})", s.c_lit);
  }
  const double cam_z = s.reflection_side ? 1.0 : -1.0;
  const std::string json = fmt::format(
      R"({{
  "render": {{"resolution": [{res}, {res}], "spp": {spp}, "wavelengths": {wl}, "fluorescence": "{fl}",
             "transmittance": "{tr}", "excitation_through_glass": "{glass}", "max_depth": 64}},
  "camera": {{"type": "orthographic", "position": [0, 0, {camz}], "look_at": [0, 0, {D2}], "height": 0.01}},
  "pigments": {{"dye": {{
    "extinction": {{"table": {{"lambda": [{l0}, {l1}, {l2}, {l3}], "value": [0, {eps}, {eps}, 0]}}}},
    "quantum_yield": {Q}, "emission": {emission}}}}},
  "materials": {{"boundary": {{"type": "interface"}}{glass_material}}},
  "media": {{"solution": {{"solvent": {{"absorption": {zeta}, "rayleigh": false}},
    "pigments": [{pim}]}}}},
  "shapes": [{{"type": "box", "min": [-{w}, -{w}, 0], "max": [{w}, {w}, {D}],
              "material": "boundary", "inside": "solution"}}{glass_shape}],
  "lights": [{{"type": "distant", "direction": [{dx}, 0, {dz}], "spectrum": {light}, "scale": 1}}]
}}
)",
      fmt::arg("res", s.resolution), fmt::arg("spp", s.spp), fmt::arg("wl", s.wavelengths),
      fmt::arg("fl", s.fluorescence), fmt::arg("tr", s.transmittance), fmt::arg("glass", s.excitation_through_glass), fmt::arg("camz", cam_z),
      fmt::arg("D2", s.D / 2), fmt::arg("l0", s.eps_lo - 1e-3), fmt::arg("l1", s.eps_lo), fmt::arg("l2", s.eps_hi),
      fmt::arg("l3", s.eps_hi + 1e-3), fmt::arg("eps", s.epsilon), fmt::arg("Q", s.Q),
      fmt::arg("emission", s.emission), fmt::arg("zeta", spectrum_or_number(s.zeta)), fmt::arg("pim", pigment_in_medium),
      fmt::arg("w", kHalfWidth), fmt::arg("D", s.D), fmt::arg("light", s.light),
      fmt::arg("glass_material", glass_material), fmt::arg("glass_shape", glass_shape),
      fmt::arg("dx", -std::sin(theta)), fmt::arg("dz", -std::cos(theta)));
  const std::filesystem::path path = dir / (s.name + ".json");
  std::ofstream f(path);
  f << json;
  if (!f) throw InputError(path.string(), "", "", "cannot be written");
  return path;
}

double slab_radiance(const SlabCase& s, const Scene& scene, double lambda_nm) {
  const Pigment& p = slab_pigment(scene);
  return p.quantum_yield * p.emission(float(lambda_nm)) * excitation_integral(s, scene) / (4 * M_PI * lambda_nm);
}

XYZ slab_xyz(const SlabCase& s, const Scene& scene) {
  const Pigment& p = slab_pigment(scene);
  const double A = excitation_integral(s, scene);
  const double step = 0.05;
  const int n = int(std::lround((kLambdaMax - kLambdaMin) / step));
  XYZ xyz;
  for (int i = 0; i <= n; ++i) {
    const double l = kLambdaMin + i * step;
    const double L = p.quantum_yield * p.emission(float(l)) * A / (4 * M_PI * l);
    const XYZ cmf = cie_cmf(float(l));
    const double w = (i == 0 || i == n ? 0.5 : 1.0) * step * L;
    xyz.x += w * cmf.x;
    xyz.y += w * cmf.y;
    xyz.z += w * cmf.z;
  }
  const double norm = cie_y_integral();
  return {xyz.x / norm, xyz.y / norm, xyz.z / norm};
}

Image slab_reference_image(const SlabCase& s, const Scene& scene) {
  const XYZ xyz = slab_xyz(s, scene);
  const RGB rgb = scene.settings.color_space == ColorSpace::ACEScg ? xyz_to_acescg(xyz) : xyz_to_linear_srgb(xyz);
  Image image;
  image.width = scene.settings.width;
  image.height = scene.settings.height;
  const size_t n = size_t(image.width) * image.height;
  auto layer = [&](const char* name, RGB v) {
    ImageLayer l{name, {"R", "G", "B"}, std::vector<float>(n * 3)};
    for (size_t i = 0; i < n; ++i) {
      l.pixels[3 * i] = float(v.r);
      l.pixels[3 * i + 1] = float(v.g);
      l.pixels[3 * i + 2] = float(v.b);
    }
    image.layers.push_back(std::move(l));
  };
  layer("total", rgb);
  layer("fluorescence", rgb);
  layer("nonfluorescence", RGB{});
  image.metadata.set("analytic", s.name);
  image.metadata.set("X", xyz.x);
  image.metadata.set("Y", xyz.y);
  image.metadata.set("Z", xyz.z);
  return image;
}

}  // namespace chlorovdb
