// Where a grid medium sits and how far it reaches: the grid's own length unit,
// the warning for a grid out of scale with the scene, and a medium box that holds
// the whole support of its interpolation whatever the grid's index offset.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "grids/vdb_file.h"
#include "scene/medium_param.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

std::filesystem::path scratch(const std::string& name) { return test::scratch_dir("grid_medium_tests") / name; }

// A slab of 16 voxels of value `c` along x (voxel centres at world x = 0, h, .., 15h),
// 8 x 8 voxels across, stored at index offset `offset` along x.
std::filesystem::path write_slab(const std::string& name, int offset, float h, float c,
                                 const std::string& length_unit = "") {
  DenseGrid d({16, 8, 8}, c);
  d.origin = {offset, -4, -4};
  d.world_from_index = Transform::scale(Vec3(h)) * Transform::translate({-float(offset), 0.f, 0.f});
  d.metadata.name = "density";
  d.metadata.unit = "uM";
  d.metadata.length_unit = length_unit;
  const auto path = scratch(name + ".vdb");
  write_concentration_grid(path, d);
  return path;
}

std::string slab_scene(const std::filesystem::path& grid, const std::string& interpolation,
                       const std::string& scene_unit = "m", const std::string& grid_extra = "") {
  return R"({"length_unit": ")" + scene_unit + R"(",
    "camera": {"position": [0.08, 0, 0.3], "look_at": [0.08, 0, 0]},
    "pigments": {"dye": {"extinction": 1000}},
    "media": {"slab": {"solvent": "none", "interpolation": ")" + interpolation + R"(",
                       "pigments": [{"pigment": "dye", "grid": {"file": ")" + grid.string() + R"(")" + grid_extra + R"(}}]}}
  })";
}

Scene load(const std::string& name, const std::string& json) {
  const auto path = scratch(name + ".json");
  std::ofstream(path) << json;
  return load_scene(path);
}

// The grid's value integrated along the world x axis at y = z = 0.3 h through the medium's box:
// midpoint rule on steps that put every kink of the interpolant (integers for trilinear,
// half-integers for nearest) on a step boundary, so the sum is exact up to rounding.
double optical_depth_in_values(const Medium& m, const Bounds3& box, float h) {
  const int steps_per_voxel = 64;
  const double dx = double(h) / steps_per_voxel;
  const int n = int(std::lround((box.hi.x - box.lo.x) / dx));
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p{float(box.lo.x + (i + 0.5) * dx), 0.3f * h, 0.3f * h};
    sum += m.channel_values(m.index_point(p))[0] * dx;
  }
  return sum;
}

}  // namespace

// PHYSICS.md §7: a trilinear grid reproduces the linear field between voxel centres, so the
// slab's hat functions integrate to exactly 16 voxels of optical depth; so do nearest lookups'
// cells. The box must not cut either, wherever the data sits in index space (a box made of the
// leaf bounds plus half a voxel cut the trilinear fade where the data ends on a leaf boundary:
// 15.75 voxels at offset 0).
TEST(GridMedium, BoxHoldsTheInterpolantsSupportAtEveryIndexOffset) {
  const float h = 0.01f, c = 2.f;
  for (const std::string interpolation : {"trilinear", "nearest"})
    for (const int offset : {0, 3, 5, 8, -8, -3, 1000}) {
      const std::string name = "slab_" + interpolation + "_" + std::to_string(offset);
      const auto grid = write_slab(name, offset, h, c);
      const Scene scene = load(name, slab_scene(grid, interpolation));
      ASSERT_EQ(scene.media.size(), 1u);
      const auto box = medium_bounds(scene.media[0]);
      ASSERT_TRUE(box);
      const float r = interpolation == "trilinear" ? 1.f : 0.5f;
      // The box holds the support (it may hold more: the stored leaf voxels around the data).
      EXPECT_LE(box->lo.x, -r * h + 1e-6f) << name;
      EXPECT_GE(box->hi.x, (15.f + r) * h - 1e-6f) << name;
      if (offset % 8 == 0) {  // data on leaf boundaries: the box is exactly the support
        EXPECT_NEAR(box->lo.x, -r * h, 1e-6f) << name;
        EXPECT_NEAR(box->hi.x, (15.f + r) * h, 1e-6f) << name;
      }
      const double depth = optical_depth_in_values(scene.media[0], *box, h) / (c * h);
      EXPECT_NEAR(depth, 16.0, 1e-4) << name << ": the slab's optical depth in voxels";
      // Outside the box every lookup is the background: nothing attenuates past it.
      for (const float x : {box->lo.x - 1e-4f * h, box->hi.x + 1e-4f * h})
        EXPECT_EQ(scene.media[0].channel_values(scene.media[0].index_point({x, 0.3f * h, 0.3f * h}))[0], 0.f)
            << name << " at x = " << x;
      // `chlorovdb info` reports the box the renderer uses.
      const GridInfo info = inspect_vdb(grid).grids.at(0);
      const Bounds3& reported = info.medium_world_bounds[int(interpolation == "trilinear" ? Interpolation::trilinear
                                                                                         : Interpolation::nearest)];
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(reported.lo[a], box->lo[a], 1e-6f) << name << " axis " << a;
        EXPECT_NEAR(reported.hi[a], box->hi[a], 1e-6f) << name << " axis " << a;
      }
    }
}

// A grid's transform is in its own length unit: the scene's key, else its
// "length_unit" metadata, else metres; the scene's length_unit never scales it.
TEST(GridMedium, GridLengthUnitComesFromTheGridNotTheScene) {
  auto hi_x = [](const Scene& s) { return medium_bounds(s.media[0])->hi.x; };
  const auto metres = write_slab("unit_m", 0, 0.01f, 1.f);
  const auto centimetres = write_slab("unit_cm", 0, 1.f, 1.f, "cm");
  const float expected = 16.f * 0.01f;  // 16 voxels of 1 cm (trilinear: 15 + 1)
  EXPECT_NEAR(hi_x(load("m_in_cm", slab_scene(metres, "trilinear", "cm"))), expected, 1e-6f);
  EXPECT_NEAR(hi_x(load("m_in_m", slab_scene(metres, "trilinear", "m"))), expected, 1e-6f);
  EXPECT_NEAR(hi_x(load("cm_meta", slab_scene(centimetres, "trilinear", "m"))), expected, 1e-6f);
  // The scene's key overrides the metadata.
  EXPECT_NEAR(hi_x(load("cm_as_mm", slab_scene(centimetres, "trilinear", "m", R"(, "length_unit": "mm")"))),
              16.f * 0.001f, 1e-7f);
  const std::string bad = slab_scene(metres, "trilinear", "m", R"(, "length_unit": "inch")");
  EXPECT_THROW(load("bad_unit", bad), InputError);
}

TEST(GridMedium, GridOutOfScaleWithTheSceneIsWarnedAbout) {
  const auto metres = write_slab("warn_m", 0, 0.01f, 1.f);
  EXPECT_TRUE(load("fits", slab_scene(metres, "trilinear")).warnings.empty());
  // The same grid read as micrometres: 16 µm across in front of a camera 0.3 m away.
  const Scene tiny = load("tiny", slab_scene(metres, "trilinear", "m", R"(, "length_unit": "um")"));
  ASSERT_EQ(tiny.warnings.size(), 1u);
  EXPECT_NE(tiny.warnings[0].find("length unit"), std::string::npos) << tiny.warnings[0];
  EXPECT_NE(tiny.warnings[0].find("media.slab"), std::string::npos) << tiny.warnings[0];
}
