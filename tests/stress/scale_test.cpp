// Stress: voxel sizes from 1e-6 m to 1e3 m, scenes far from the origin (1e5 m,
// in world and in index space), and grazing rays along faces, edges and
// silhouettes of media, dielectrics and spheres.
#include <gtest/gtest.h>

#include <typeinfo>

#include "core/error.h"
#include "grids/vdb_file.h"
#include "stress_util.h"

using namespace chlorovdb;
using namespace chlorovdb::stress;

namespace {

std::string sanitize(std::string s) {
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

// An 8^3 grid of a smooth blob (peak at the centre, 0 at the corners) with voxel
// size h, placed with its index origin at `index_origin` and its world origin at
// `offset`, scaled so the optical depth through the centre is about `tau`.
// `length_unit` is stored as the grid's metadata (empty: none, i.e. metres).
std::filesystem::path write_blob_grid(const std::string& name, double h, Vec3 offset, Coord index_origin, double tau,
                                      const std::string& length_unit = "") {
  DenseGrid g({8, 8, 8});
  g.origin = index_origin;
  double column = 0;
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        const double dx = x - 3.5, dy = y - 3.5, dz = z - 3.5;
        const double v = std::max(0.0, 1.0 - (dx * dx + dy * dy + dz * dz) / 36.0);
        g.at(x, y, z) = float(v);
        if (x == 3 && y == 3) column += v;
      }
  const double molar_peak = tau / (kSigmaPerMolar * column * h);
  for (float& v : g.values) v = float(v * molar_peak);
  // World = offset + h * (index - index_origin): voxel centres of the box span offset + [0, 7h].
  g.world_from_index = Transform::translate(offset) * Transform::scale(Vec3(float(h))) *
                       Transform::translate(Vec3(-float(index_origin[0]), -float(index_origin[1]), -float(index_origin[2])));
  g.metadata.name = "density";
  g.metadata.unit = "M";
  g.metadata.length_unit = length_unit;
  const auto path = scratch_dir() / (name + ".vdb");
  write_concentration_grid(path, g);
  return path;
}

// The grid medium fills its own box (no shape bounds it); a diffuse floor just
// below it; a white environment and a UV distant light.
// Positions, h and offset are in the file's `length_unit`; the grid's transform is in its own
// (its metadata, metres by default: docs/scene-format.md), so the caller writes it in the same unit.
std::string blob_scene(const std::filesystem::path& grid, double h, Vec3 offset, const std::string& camera_type,
                       const std::string& length_unit = "m") {
  const double cx = offset.x + 3.5 * h, cy = offset.y + 3.5 * h, cz = offset.z + 3.5 * h;
  return subst(R"({
    "length_unit": "$UNIT",
    "render": {"resolution": [8, 8], "wavelengths": 4, "fluorescence": "auto"},
    "camera": {"type": "$CAM", "position": [$PX, $PY, $PZ], "look_at": [$CX, $CY, $CZ], $ZOOM},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 830], "value": [1e4, 1e4]}},
                         "quantum_yield": 0.5, "emission": {"gaussian": [650, 20]}}},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.8}},
    "media": {"blob": {"solvent": "none", "pigments": [{"pigment": "dye", "grid": {"file": "$GRID", "name": "density"}}]}},
    "shapes": [{"type": "quad", "corner": [$FX0, $FY, $FZ0], "edge_u": [0, 0, $FW], "edge_v": [$FW, 0, 0], "material": "floor"}],
    "lights": [{"type": "environment", "spectrum": 1},
               {"type": "distant", "direction": [0.3, -1, -0.2], "spectrum": {"gaussian": [300, 10]}, "scale": 2}]
  })",
               {{"$UNIT", length_unit},
                {"$CAM", camera_type},
                {"$PX", num(cx + 6 * h)},
                {"$PY", num(cy + 10 * h)},
                {"$PZ", num(cz + 30 * h)},
                {"$CX", num(cx)},
                {"$CY", num(cy)},
                {"$CZ", num(cz)},
                {"$ZOOM", camera_type == "orthographic" ? "\"height\": " + num(12 * h) : std::string("\"fov\": 25")},
                {"$GRID", grid.string()},
                {"$FX0", num(cx - 40 * h)},
                {"$FZ0", num(cz - 40 * h)},
                {"$FY", num(offset.y - 0.5 * h)},
                {"$FW", num(80 * h)}});
}

}  // namespace

// ---------------------------------------------------------------------------
// Voxel sizes 1e-6 m .. 1e3 m (the same optical depth, so only the scale changes).
// ---------------------------------------------------------------------------
void voxel_sizes(const std::string& camera) {
  for (double h : {1e-6, 1e-4, 1e-2, 1.0, 1e3}) {
    RenderCase c;
    c.name = "voxel_" + sanitize(num(h)) + "m_" + camera;
    // OpenVDB cannot store voxels under ~1e-5 of its unit (its maps refuse |det| < ~1e-15),
    // so micrometre voxels are written as 1 "um" (the grid's length_unit metadata) and the scene says "um".
    const bool micro = h < 1e-5;
    const double h_file = micro ? h * 1e6 : h;
    const auto grid = write_blob_grid(c.name, h_file, Vec3(0.f), {0, 0, 0}, 3.0 * h_file / h, micro ? "um" : "");
    c.json = blob_scene(grid, h_file, Vec3(0.f), camera, micro ? "um" : "m");
    if (const auto o = try_case(c)) EXPECT_GT(o->mean_luminance, 0.0) << c.name << ": black image";
  }
}

TEST(Stress, VoxelSizesPerspective) { voxel_sizes("perspective"); }
TEST(Stress, VoxelSizesOrthographic) { voxel_sizes("orthographic"); }

// write_concentration_grid builds an OpenVDB AffineMap, which refuses |det| below
// ~1e-15 ("nearly singular"): 1 µm voxels in metres (det 1e-18) cannot be stored, and
// OpenVDB's own uniform scale map refuses them too. That is OpenVDB's limit; the
// library must report it as an InputError naming the file and the way out
// (length_unit), not let openvdb::ArithmeticError escape.
TEST(Stress, MicrometreVoxelsInMetresGiveAnInputError) {
  DenseGrid g({2, 2, 2}, 1.f);
  g.world_from_index = Transform::scale(Vec3(1e-6f));
  g.metadata.name = "density";
  try {
    write_concentration_grid(scratch_dir() / "micrometre_in_metres.vdb", g);
  } catch (const InputError&) {
    // Refused with a message: fine.
  } catch (const std::exception& e) {
    ADD_FAILURE() << "write_concentration_grid with 1e-6 m voxels threw " << typeid(e).name() << ": " << e.what()
                  << " (not an InputError)";
  }
}

// docs/scene-format.md: a grid's transform is in its own length unit (its
// "length_unit" metadata, metres by default); the scene's length_unit applies to
// the scene's own positions. The same physical scene written in metres and in
// centimetres (grid voxel 0.01 m = 1 cm, metadata "cm") must render alike.
TEST(Stress, GridLengthUnitMetadataPlacesGrids) {
  RenderCase m, cm;
  m.name = "length_unit_m";
  cm.name = "length_unit_cm";
  // Same optical depth 3 through the centre in both (the grid values are concentrations).
  const auto grid_m = write_blob_grid(m.name, 0.01, Vec3(0.f), {0, 0, 0}, 3.0);
  const auto grid_cm = write_blob_grid(cm.name, 1.0, Vec3(0.f), {0, 0, 0}, 3.0 / 0.01, "cm");
  m.json = blob_scene(grid_m, 0.01, Vec3(0.f), "perspective", "m");
  cm.json = blob_scene(grid_cm, 1.0, Vec3(0.f), "perspective", "cm");
  m.spp = cm.spp = 64;
  m.seconds = cm.seconds = 30;
  const RenderOutcome a = render_case(m), b = render_case(cm);
  EXPECT_NEAR(b.mean_luminance, a.mean_luminance, 0.05 * a.mean_luminance)
      << "the same scene in cm renders differently: is the grid's length_unit metadata applied?";
}

// ---------------------------------------------------------------------------
// Far from the origin: float spacing at 1e5 m is 7.8 mm, so a 0.8 m grid there
// has ~100 representable positions across it. Also far in index space (voxel
// indices near 1e6, where float spacing is 1/16 voxel).
// ---------------------------------------------------------------------------
struct FarCase {
  const char* label;
  Vec3 offset;
  Coord index_origin;
};

TEST(Stress, FarFromOrigin) {
  const FarCase cases[] = {{"x1e5", Vec3(1e5f, 0.f, 0.f), {0, 0, 0}},
                           {"xyz1e5", Vec3(1e5f, 1e5f, 1e5f), {0, 0, 0}},
                           {"minus_xyz1e5", Vec3(-1e5f, -1e5f, -1e5f), {0, 0, 0}},
                           {"index1e6", Vec3(0.f), {1000000, -1000000, 1000000}},
                           {"both", Vec3(1e5f, 0.f, -1e5f), {1000000, 0, -1000000}}};
  for (const FarCase& f : cases) {
    RenderCase c;
    c.name = std::string("far_") + f.label;
    const double h = 0.1;
    const auto grid = write_blob_grid(c.name, h, f.offset, f.index_origin, 3.0);
    c.json = blob_scene(grid, h, f.offset, "perspective");
    try_case(c);
  }
}

// A glass cuvette of dye 1e5 m from the origin (surfaces, refraction and media there).
TEST(Stress, GlassCuvetteFarFromOrigin) {
  RenderCase c;
  c.name = "glass_cuvette_far";
  c.json = R"({
    "render": {"resolution": [8, 8], "wavelengths": 4},
    "camera": {"position": [100000.5, 100000.8, 100003], "look_at": [100000, 100000, 100000], "fov": 30},
    "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
    "materials": {"glass": {"type": "dielectric", "ior": 1.5}, "floor": {"type": "diffuse", "albedo": 0.5}},
    "media": {"s": {"solvent": "water", "pigments": [{"pigment": "chl", "concentration": 25}]}},
    "shapes": [{"type": "box", "min": [99999.5, 99999.5, 99999.5], "max": [100000.5, 100000.5, 100000.5],
                "material": "glass", "inside": "s"},
               {"type": "quad", "corner": [99990, 99999.49, 99990], "edge_u": [0, 0, 20], "edge_v": [20, 0, 0],
                "material": "floor"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })";
  render_case(c);
}

// ---------------------------------------------------------------------------
// Grazing rays, traced one by one: along faces and edges of a medium box and of
// a glass box, tangent to a sphere, starting on a face. Directions tilt by
// 0, ±1e-9 .. ±1e-2 rad from exactly parallel.
// ---------------------------------------------------------------------------
namespace {

void trace_grazing(const std::string& name, const std::string& json, const std::vector<Ray>& rays, int medium_of_origin) {
  Watchdog watchdog(name, 20);
  const Scene scene = load_scene(write_scene(name, json));
  const double bound = luminance_bound(scene);
  PathStats stats;
  int ray_index = 0;
  for (const Ray& base : rays) {
    for (int s = 0; s < 64; ++s) {
      Rng rng = sample_rng(3, ray_index, 0, s);
      SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 4);
      const PathRadiance L = trace_path(scene, base, medium_of_origin, lambda, rng, stats);
      const SampledSpectrum total = L.fluorescence + L.other;
      ASSERT_FALSE(total.has_nonfinite()) << name << ": ray " << ray_index << " o=(" << base.o.x << ", " << base.o.y
                                          << ", " << base.o.z << ") d=(" << base.d.x << ", " << base.d.y << ", "
                                          << base.d.z << ") sample " << s;
      const XYZ xyz = to_xyz(total, lambda);
      ASSERT_TRUE(std::isfinite(xyz.y)) << name << ": ray " << ray_index;
      // One sample, not a mean: allow the per-sample spread of the estimators (x1000) before calling it a blow-up.
      EXPECT_LE(xyz.y, 1000 * bound) << name << ": ray " << ray_index << " sample " << s;
    }
    ++ray_index;
  }
}

std::vector<Ray> grazing_rays_along_box(float half) {
  std::vector<Ray> rays;
  const float tilts[] = {0.f, 1e-9f, -1e-9f, 1e-7f, -1e-7f, 1e-5f, -1e-5f, 1e-3f, -1e-3f, 1e-2f};
  for (float t : tilts) {
    rays.push_back({{-3.f, half, 0.f}, normalize(Vec3{1.f, t, 0.f})});         // along the top face
    rays.push_back({{-3.f, half, half}, normalize(Vec3{1.f, t, t})});          // along an edge
    rays.push_back({{-3.f, -3.f, -3.f}, normalize(Vec3{1.f, 1.f + t, 1.f})});  // through a corner
    rays.push_back({{0.f, half, 0.f}, normalize(Vec3{1.f, t, 0.f})});          // starting on the face
    rays.push_back({{half, 0.f, 0.f}, normalize(Vec3{t, 1.f, 0.f})});          // starting on a face, along it
  }
  return rays;
}

}  // namespace

TEST(Stress, GrazingRaysMediumBox) {
  trace_grazing("grazing_medium_box", R"({
    "render": {"wavelengths": 4, "fluorescence": "full"},
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 830], "value": [1e4, 1e4]}},
                         "quantum_yield": 0.8, "emission": {"gaussian": [650, 20]}}},
    "materials": {"boundary": {"type": "interface"}},
    "media": {"dye": {"solvent": "water", "pigments": [{"pigment": "dye", "concentration": 100}]}},
    "shapes": [{"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "boundary", "inside": "dye"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })",
                grazing_rays_along_box(0.5f), -1);
}

TEST(Stress, GrazingRaysGlassBoxWithMedium) {
  trace_grazing("grazing_glass_box", R"({
    "render": {"wavelengths": 4, "fluorescence": "full"},
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
    "materials": {"glass": {"type": "dielectric", "ior": 1.5}},
    "media": {"s": {"solvent": "water", "pigments": [{"pigment": "chl", "concentration": 25}]}},
    "shapes": [{"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "glass", "inside": "s"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })",
                grazing_rays_along_box(0.5f), -1);
}

TEST(Stress, GrazingRaysTangentToSpheres) {
  std::vector<Ray> rays;
  for (float t : {0.f, 1e-7f, -1e-7f, 1e-5f, -1e-5f, 1e-3f}) {
    rays.push_back({{-3.f, 1.f + t, 0.f}, {1.f, 0.f, 0.f}});       // tangent to the unit sphere
    rays.push_back({{-3.f, 0.f, 3.f + 0.5f + t}, {1.f, 0.f, 0.f}});  // tangent to the glass sphere
    rays.push_back({{0.f, 1.f, 0.f}, normalize(Vec3{1.f, t, 0.f})});  // starting on the sphere, tangent
  }
  trace_grazing("grazing_spheres", R"({
    "render": {"wavelengths": 4, "fluorescence": "full"},
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 830], "value": [1e4, 1e4]}},
                         "quantum_yield": 0.8, "emission": {"gaussian": [650, 20]}}},
    "materials": {"boundary": {"type": "interface"}, "glass": {"type": "dielectric", "ior": 1.5}},
    "media": {"dye": {"solvent": "none", "pigments": [{"pigment": "dye", "concentration": 10}]}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "boundary", "inside": "dye"},
               {"type": "sphere", "center": [0, 0, 3], "radius": 0.5, "material": "glass", "inside": "dye"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })",
                rays, -1);
}

// The camera exactly on a medium's face, looking along it (every camera ray grazes).
TEST(Stress, CameraOnMediumFaceLookingAlongIt) {
  RenderCase c;
  c.name = "camera_on_face";
  c.json = R"({
    "render": {"resolution": [8, 8], "wavelengths": 4, "fluorescence": "full"},
    "camera": {"type": "orthographic", "position": [0, 0.5, 2], "look_at": [0, 0.5, 0], "height": 0.5},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 830], "value": [1e4, 1e4]}},
                         "quantum_yield": 0.8, "emission": {"gaussian": [650, 20]}}},
    "materials": {"boundary": {"type": "interface"}},
    "media": {"dye": {"solvent": "water", "pigments": [{"pigment": "dye", "concentration": 100}]}},
    "shapes": [{"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "boundary", "inside": "dye"}],
    "lights": [{"type": "environment", "spectrum": 1}]
  })";
  render_case(c);
}
