// export-pbrt: the text has pbrt-v4's structure and the right counts.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "analysis/analytic_slab.h"
#include "analysis/pbrt_export.h"
#include "core/error.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

std::filesystem::path write(const std::string& name, const std::string& json) {
  const auto dir = chlorovdb::test::scratch_dir("analysis_tests");
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << json;
  return path;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

// Every "[ ... ]" list of a spectrum parameter holds (lambda, value) pairs.
void expect_balanced(const std::string& text) {
  EXPECT_EQ(count(text, "["), count(text, "]"));
  EXPECT_EQ(count(text, "AttributeBegin"), count(text, "AttributeEnd"));
  size_t quotes = 0;
  for (char c : text) quotes += c == '"';
  EXPECT_EQ(quotes % 2, 0u);
  const std::regex spectrum(R"("spectrum [A-Za-z_]+" \[([^\]]*)\])");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), spectrum); it != std::sregex_iterator(); ++it) {
    std::istringstream values((*it)[1].str());
    size_t n = 0;
    for (double v; values >> v;) ++n;
    EXPECT_GT(n, 2u);
    EXPECT_EQ(n % 2, 0u) << (*it)[0].str().substr(0, 60);
  }
}

constexpr const char* kScene = R"({
  "length_unit": "cm",
  "render": {"resolution": [64, 48], "spp": 16, "max_depth": 12},
  "camera": {"position": [0, 5, 20], "look_at": [0, 2, 0], "fov": 30},
  "pigments": {"ink": {"extinction": {"gaussian": [500, 30]}, "quantum_yield": 0}},
  "materials": {
    "floor": {"type": "diffuse", "albedo": 0.4},
    "glass": {"type": "dielectric", "ior": 1.5},
    "flint": {"type": "dielectric", "ior": {"sellmeier": {"B": [1.03, 0.23, 1.01], "C": [0.006, 0.02, 103.5]}}}
  },
  "media": {"water": {"pigments": [{"pigment": "ink", "concentration": 2}]}},
  "shapes": [
    {"type": "quad", "corner": [-20, 0, -20], "edge_u": [0, 0, 40], "edge_v": [40, 0, 0], "material": "floor"},
    {"type": "box", "min": [-2, 0, -2], "max": [2, 4, 2], "material": "glass", "inside": "water"},
    {"type": "sphere", "center": [5, 1, 0], "radius": 1, "material": "flint"},
    {"type": "disk", "center": [0, 10, 0], "normal": [0, -1, 0], "radius": 2, "emission": {"spectrum": "D65", "scale": 2}}
  ],
  "lights": [
    {"type": "point", "position": [3, 8, 3], "spectrum": {"blackbody": 3000}, "scale": 50},
    {"type": "spot", "position": [-3, 8, 3], "look_at": [0, 0, 0], "cone_angle": 25, "falloff_angle": 5},
    {"type": "distant", "direction": [0, -1, -1], "spectrum": "D65", "scale": 0.5},
    {"type": "environment", "spectrum": "D65", "scale": 0.01}
  ]
})";

}  // namespace

TEST(PbrtExport, SmallSceneHasPbrtStructureAndCounts) {
  const auto file = write("pbrt_export_scene.json", kScene);
  const Scene scene = load_scene(file);
  const PbrtExport e = export_pbrt(scene, file, {});
  const std::string& t = e.text;
  expect_balanced(t);
  // Camera: mirrored x before LookAt, then the camera, before the world block.
  const size_t scale = t.find("Scale -1 1 1"), look = t.find("LookAt"), camera = t.find("Camera \"perspective\""),
               world = t.find("WorldBegin");
  ASSERT_NE(scale, std::string::npos);
  EXPECT_LT(scale, look);
  EXPECT_LT(look, camera);
  EXPECT_LT(camera, world);
  EXPECT_NE(t.find("\"float fov\" [30]"), std::string::npos);
  EXPECT_NE(t.find("\"integer xresolution\" [64] \"integer yresolution\" [48]"), std::string::npos);
  EXPECT_NE(t.find("\"integer pixelsamples\" [16]"), std::string::npos);
  EXPECT_NE(t.find("\"integer maxdepth\" [12]"), std::string::npos);
  // Shapes: quad, box, disk as triangle meshes; one exact sphere.
  EXPECT_EQ(count(t, "Shape \"trianglemesh\""), 3u);
  EXPECT_EQ(count(t, "Shape \"sphere\""), 1u);
  EXPECT_NE(t.find("\"float radius\" [0.01]"), std::string::npos);  // 1 cm in metres
  // Materials, each once; media; lights.
  EXPECT_EQ(count(t, "MakeNamedMaterial"), 3u);
  EXPECT_NE(t.find("\"string type\" \"dielectric\" \"float eta\" [1.5]"), std::string::npos);
  EXPECT_NE(t.find("\"string type\" \"dielectric\" \"spectrum eta\""), std::string::npos);
  EXPECT_EQ(count(t, "MakeNamedMedium \"water\" \"string type\" \"homogeneous\""), 1u);
  EXPECT_NE(t.find("MediumInterface \"water\" \"\""), std::string::npos);
  EXPECT_EQ(count(t, "LightSource \"point\""), 1u);
  EXPECT_EQ(count(t, "LightSource \"spot\""), 1u);
  EXPECT_EQ(count(t, "LightSource \"distant\""), 1u);
  EXPECT_EQ(count(t, "LightSource \"infinite\""), 1u);
  EXPECT_EQ(count(t, "AreaLightSource \"diffuse\""), 1u);
  EXPECT_NE(t.find("\"float conedeltaangle\" [5]"), std::string::npos);
  // Every index list refers to existing vertices, three per triangle.
  const std::regex mesh(R"re("point3 P" \[([^\]]*)\]\s*"integer indices" \[([^\]]*)\])re");
  size_t meshes = 0;
  for (auto it = std::sregex_iterator(t.begin(), t.end(), mesh); it != std::sregex_iterator(); ++it, ++meshes) {
    std::istringstream p((*it)[1].str()), i((*it)[2].str());
    size_t coords = 0, indices = 0;
    long max_index = -1;
    for (double v; p >> v;) ++coords;
    for (long v; i >> v; ++indices) max_index = std::max(max_index, v);
    EXPECT_EQ(coords % 3, 0u);
    EXPECT_EQ(indices % 3, 0u);
    EXPECT_LT(max_index, long(coords / 3));
  }
  EXPECT_EQ(meshes, 3u);
}

TEST(PbrtExport, RefusesFluorescenceUnlessIgnoredAndDumpsGrids) {
  SlabCase slab = analytic_case("slab_linear");
  slab.name = "pbrt_export_grid";
  const auto dir = chlorovdb::test::scratch_dir("analysis_tests");
  const auto file = write_slab_scene(slab, dir);
  const Scene scene = load_scene(file);
  EXPECT_THROW(export_pbrt(scene, file, {}), InputError);
  PbrtExportOptions o;
  o.ignore_fluorescence = true;
  const PbrtExport e = export_pbrt(scene, file, o);
  expect_balanced(e.text);
  EXPECT_NE(e.text.find("\"string type\" \"uniformgrid\""), std::string::npos);
  EXPECT_NE(e.text.find("\"integer nx\" [4] \"integer ny\" [4] \"integer nz\" [11]"), std::string::npos);
  // The solvent's flat absorption cannot ride on the concentration grid: reported, not hidden.
  ASSERT_FALSE(e.warnings.empty());
  const size_t at = e.text.find("\"float density\" [");
  ASSERT_NE(at, std::string::npos);
  std::istringstream values(e.text.substr(at + 17, e.text.find(']', at) - at - 17));
  size_t n = 0;
  for (double v; values >> v;) ++n;
  EXPECT_EQ(n, 4u * 4u * 11u);
  o.max_grid_voxels = 100;
  EXPECT_THROW(export_pbrt(scene, file, o), InputError);
}
