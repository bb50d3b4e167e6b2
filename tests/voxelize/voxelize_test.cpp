// Converter tests: volumes, shell thickness, non-cubic voxels, spills and round trips through
// .vdb files (read back with load_concentration_grid, so values, transform and metadata are checked
// as the renderer will see them).
#include <cmath>
#include <fstream>

#include "core/constants.h"
#include "voxelize_test_util.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// Volume of the polyhedron make_uv_sphere builds is within 3e-4 of the sphere's at 128 x 256.
TriangleMesh fine_sphere(Vec3 center, float radius) { return make_uv_sphere(center, radius, 128, 256); }

}  // namespace

// R / h = 20 (40 voxels across): the summed fog is the sphere's volume within 1 %.
TEST(VoxelizeSolid, SphereVolumeWithinOnePercent) {
  const float R = 0.05f;
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.0025f));
  o.profile.concentration = 5.f;
  const auto path = temp_path("sphere.vdb");
  const VoxelizeReport r = voxelize_mesh(fine_sphere({0.0011f, -0.0007f, 0.0003f}, R), o, path);
  const double analytic = 4.0 / 3.0 * kPiD * R * R * R;

  const VoxelGrid g = load_concentration_grid(path, "density");
  const double volume = integral(g) / 5.0;
  EXPECT_NEAR(volume / analytic, 1.0, 0.01);
  EXPECT_NEAR(r.filled_volume / analytic, 1.0, 0.01);
  EXPECT_NEAR(r.amount / 5.0 / analytic, 1.0, 0.01);
  // The interior holds exactly C; nothing exceeds it.
  EXPECT_EQ(voxel_at(g, {0.f, 0.f, 0.f}), 5.f);
  EXPECT_FLOAT_EQ(g.max_value(), 5.f);
  EXPECT_EQ(count_voxels(g, [](float v) { return v > 0.f; }), r.active_voxels);
  // Nothing beyond the voxels the sphere's surface passes through: R / h = 20 around the centre.
  EXPECT_EQ(r.index_lo, (Coord{-20, -20, -20}));
  EXPECT_EQ(r.index_hi, (Coord{20, 20, 20}));
  EXPECT_EQ(r.unresolved_voxels, 0);
}

// An axis-aligned box whose faces cut voxels at arbitrary fractions: 40 x 30 x 35 voxels.
TEST(VoxelizeSolid, CubeVolumeWithinOnePercent) {
  const Bounds3 box{{-0.0413f, -0.0291f, -0.0337f}, {0.0387f, 0.0309f, 0.0363f}};
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.002f));
  const auto path = temp_path("cube.vdb");
  const VoxelizeReport r = voxelize_mesh(make_box(box), o, path);
  const Vec3 d = box.diagonal();
  const double analytic = double(d.x) * d.y * d.z;
  const VoxelGrid g = load_concentration_grid(path, "density");
  EXPECT_NEAR(integral(g) / analytic, 1.0, 0.01);
  EXPECT_NEAR(r.filled_volume / analytic, 1.0, 0.01);
  // The face x = -0.0413 leaves 0.15 of voxel i = -21 (extent [-0.043, -0.041]) inside.
  EXPECT_NEAR(voxel_at(g, {-0.042f, 0.f, 0.f}), 0.15f, 1e-4f);
  EXPECT_EQ(voxel_at(g, {-0.040f, 0.f, 0.f}), 1.f);
  EXPECT_EQ(voxel_at(g, {-0.044f, 0.f, 0.f}), 0.f);
}

// A box wound inside out (normals pointing in) fills the same way, edges included.
TEST(VoxelizeSolid, InwardWindingFillsTheSameWay) {
  TriangleMesh box = make_box({{0.f, 0.f, 0.f}, {0.02f, 0.01f, 0.015f}});
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  const VoxelizeReport outward = voxelize_mesh(box, o, temp_path("box_out.vdb"));
  for (size_t t = 0; t < box.indices.size(); t += 3) std::swap(box.indices[t + 1], box.indices[t + 2]);
  const VoxelizeReport inward = voxelize_mesh(box, o, temp_path("box_in.vdb"));
  EXPECT_NEAR(inward.filled_volume / outward.filled_volume, 1.0, 1e-9);
  const VoxelGrid g = load_concentration_grid(temp_path("box_in.vdb"), "density");
  EXPECT_NEAR(g.voxel(0, 0, 7), 0.25f + 1.f / 36.f, 1e-4f);
}

// Non-cubic voxels (2 x 1 x 3 mm): still within 1 % of the sphere.
TEST(VoxelizeSolid, SphereVolumeWithNonCubicVoxels) {
  const float R = 0.05f;
  VoxelizeOptions o = options_with(VoxelizeMode::solid, {0.002f, 0.001f, 0.003f});
  const auto path = temp_path("sphere_aniso.vdb");
  const VoxelizeReport r = voxelize_mesh(fine_sphere({0.f, 0.f, 0.f}, R), o, path);
  const double analytic = 4.0 / 3.0 * kPiD * R * R * R;
  const VoxelGrid g = load_concentration_grid(path, "density");
  EXPECT_NEAR(integral(g) / analytic, 1.0, 0.01);
  EXPECT_NEAR(r.filled_volume / analytic, 1.0, 0.01);
  // The transform carries the non-uniform scale.
  EXPECT_NEAR(g.world_from_index().point({1, 1, 1}).x, 0.002f, 1e-7f);
  EXPECT_NEAR(g.world_from_index().point({1, 1, 1}).y, 0.001f, 1e-7f);
  EXPECT_NEAR(g.world_from_index().point({1, 1, 1}).z, 0.003f, 1e-7f);
}

// A 1 mm shell on a 10 x 10 cm quad with 0.25 mm voxels, measured across the shell along the normal.
TEST(VoxelizeShell, ThicknessWithinOneVoxel) {
  const float t = 0.001f, h = 0.00025f, y0 = 0.00031f;
  VoxelizeOptions o = options_with(VoxelizeMode::shell, Vec3(h));
  o.thickness = t;
  const auto path = temp_path("shell_quad.vdb");
  const VoxelizeReport r = voxelize_mesh(make_quad({-0.05f, y0, -0.05f}, {0, 0, 0.1f}, {0.1f, 0, 0}), o, path);
  const VoxelGrid g = load_concentration_grid(path, "density");
  double across = 0;
  int solid_voxels = 0;
  for (int j = -20; j <= 20; ++j) {
    const float v = g.voxel(0, j, 0);
    across += v * h;
    solid_voxels += v >= 0.5f ? 1 : 0;
  }
  EXPECT_NEAR(across, t, 0.01 * t);                // the amount across the shell is exact
  EXPECT_NEAR(solid_voxels * h, t, h);             // voxels at least half inside: within one voxel
  EXPECT_NEAR(line_integral(g, {0.f, y0 - 3 * t, 0.f}, {0.f, y0 + 3 * t, 0.f}), t, 0.01 * t);
  // Volume: the slab plus the half-cylinder rounding the free edge.
  const double expected = 0.1 * 0.1 * t + 0.4 * kPiD * t * t / 8.0;
  EXPECT_NEAR(r.filled_volume / expected, 1.0, 0.01);
  EXPECT_NEAR(integral(g) / expected, 1.0, 0.01);
}

// The leaf case: a tilted disk (normal not along an axis) with voxels 5x finer along y than along x
// and z. World-space distances keep the thickness right along the true normal.
TEST(VoxelizeShell, TiltedDiskWithNonCubicVoxels) {
  const float t = 0.0006f, radius = 0.03f;
  const Vec3 n = normalize(Vec3(0.3f, 1.f, 0.2f)), c{0.0003f, 0.0101f, -0.0002f};
  const TriangleMesh disk = make_disk(c, n, radius, 128);
  const double area = 0.5 * 128 * double(radius) * radius * std::sin(2 * kPiD / 128);
  const double expected = area * t + 2 * kPiD * radius * kPiD * double(t) * t / 8.0;

  VoxelizeOptions o = options_with(VoxelizeMode::shell, {0.001f, 0.0002f, 0.001f});
  o.thickness = t;
  const auto path = temp_path("leaf.vdb");
  const VoxelizeReport r = voxelize_mesh(disk, o, path);
  const VoxelGrid g = load_concentration_grid(path, "density");
  EXPECT_NEAR(r.filled_volume / expected, 1.0, 0.02);
  EXPECT_NEAR(integral(g) / expected, 1.0, 0.02);
  // Across the shell along its normal, at a few points of the disk: within one (the finest) voxel.
  const Frame f = Frame::from_z(n);
  for (const Vec3 offset : {Vec3(0.f), 0.011f * f.s, -0.017f * f.t + 0.005f * f.s}) {
    const Vec3 p = c + offset;
    const double across = line_integral(g, p - 4 * t * n, p + 4 * t * n);
    EXPECT_NEAR(across, t, 0.0002) << "at offset " << offset.x << ", " << offset.y << ", " << offset.z;
  }

  // The same leaf with cubic 0.2 mm voxels stores about 5x more voxels for the same amount.
  VoxelizeOptions fine = o;
  fine.voxel_size = Vec3(0.0002f);
  const VoxelizeReport rf = voxelize_mesh(disk, fine, temp_path("leaf_fine.vdb"));
  EXPECT_NEAR(rf.filled_volume / expected, 1.0, 0.02);
  EXPECT_GT(rf.active_voxels, 3 * r.active_voxels);
}

// A 2 mm layer on a disk footprint (normal +y), 0.5 mm voxels.
TEST(VoxelizeSpill, FootprintDepthAndVolume) {
  const float depth = 0.002f, h = 0.0005f, radius = 0.04f;
  VoxelizeOptions o = options_with(VoxelizeMode::spill, Vec3(h));
  o.depth = depth;
  o.profile.concentration = 1.f;
  const auto path = temp_path("spill.vdb");
  const VoxelizeReport r = voxelize_mesh(make_disk({0.0002f, 0.0001f, -0.0003f}, {0, 1, 0}, radius, 128), o, path);
  const VoxelGrid g = load_concentration_grid(path, "density");
  const double area = 0.5 * 128 * double(radius) * radius * std::sin(2 * kPiD / 128);
  EXPECT_NEAR(integral(g) / (area * depth), 1.0, 0.01);
  EXPECT_NEAR(r.filled_volume / (area * depth), 1.0, 0.01);
  double across = 0;
  int solid_voxels = 0;
  for (int j = -10; j <= 20; ++j) {
    across += g.voxel(0, j, 0) * h;
    solid_voxels += g.voxel(0, j, 0) >= 0.5f ? 1 : 0;
  }
  EXPECT_NEAR(across, depth, 0.01 * depth);
  EXPECT_NEAR(solid_voxels * h, depth, h);
  EXPECT_EQ(voxel_at(g, {0.f, -0.001f, 0.f}), 0.f);  // nothing below the surface
}

// --direction up on a footprint tilted 30° from horizontal: a vertical prism.
TEST(VoxelizeSpill, ExtrudesUpOnTiltedFootprint) {
  const float depth = 0.003f;
  const Vec3 u{0.f, 0.03f, 0.0519615f}, v{0.06f, 0.f, 0.f};  // |u| = |v| = 6 cm, u tilted 30°
  const TriangleMesh quad = make_quad({-0.03f, 0.01f, -0.03f}, u, v);
  VoxelizeOptions o = options_with(VoxelizeMode::spill, Vec3(0.0005f));
  o.depth = depth;
  o.spill_direction = SpillDirection::up;
  EXPECT_EQ(spill_offset(quad, o), Vec3(0.f, depth, 0.f));
  const TriangleMesh prism = extrude_footprint(quad, spill_offset(quad, o), "quad");
  EXPECT_TRUE(is_closed(prism));
  EXPECT_NEAR(detail::enclosed_volume(prism), 0.06 * 0.0519615 * depth, 1e-9);
  const VoxelizeReport r = voxelize_mesh(quad, o, temp_path("spill_up.vdb"));
  EXPECT_NEAR(r.filled_volume / (0.06 * 0.0519615 * depth), 1.0, 0.01);
}

TEST(VoxelizeSpill, FootprintWithNormalPointingDownIsFlipped) {
  // Winding facing -y, extruded up: the prism is still closed with positive volume.
  const TriangleMesh quad = make_quad({0, 0, 0}, {0.01f, 0, 0}, {0, 0, 0.01f});  // normal = x cross z = -y
  const TriangleMesh prism = extrude_footprint(quad, {0.f, 0.001f, 0.f}, "quad");
  EXPECT_TRUE(is_closed(prism));
  EXPECT_NEAR(detail::enclosed_volume(prism), 1e-7, 1e-12);
}

// Height field: local depth = sample × --depth on the plane y = origin.y.
TEST(VoxelizeSpill, HeightFieldColumnsAndVolume) {
  const auto file = temp_path("puddle.hf");
  {
    std::ofstream out(file);
    out << "# a small puddle: rows along z, columns along x\n"
           "0 0 0 0 0\n"
           "0 1 1 0.5 0\n"
           "0, 1, 1, 0.5, 0\n"
           "0 0 0 0 0\n";
  }
  const HeightField f = load_height_field(file);
  ASSERT_EQ(f.nx, 5);
  ASSERT_EQ(f.nz, 4);
  EXPECT_EQ(f.at(3, 2), 0.5f);

  const float depth = 0.004f, cell = 0.01f;
  const Vec3 origin{0.1f, 0.05f, -0.02f};
  VoxelizeOptions o = options_with(VoxelizeMode::spill, {0.0005f, 0.0002f, 0.0005f});
  o.depth = depth;
  o.height_field_cell = cell;
  o.world_from_input = Transform::translate(origin);
  o.profile.concentration = 2.f;
  const auto path = temp_path("puddle.vdb");
  const VoxelizeReport r = voxelize_file(file, o, path);
  const VoxelGrid g = load_concentration_grid(path, "density");
  // Bilinear surface: each cell holds the mean of its corners.
  double exact = 0;
  for (int j = 0; j + 1 < f.nz; ++j)
    for (int i = 0; i + 1 < f.nx; ++i)
      exact += 0.25 * (f.at(i, j) + f.at(i + 1, j) + f.at(i, j + 1) + f.at(i + 1, j + 1)) * cell * cell * depth;
  EXPECT_NEAR(r.filled_volume / exact, 1.0, 0.02);
  EXPECT_NEAR(integral(g) / 2.0 / exact, 1.0, 0.02);
  // Columns above samples (1, 1) and (3, 1): depth and depth / 2.
  auto column = [&](int i, int j) {
    return line_integral(g, origin + Vec3(i * cell, -0.001f, j * cell), origin + Vec3(i * cell, 0.006f, j * cell)) / 2.0;
  };
  EXPECT_NEAR(column(1, 1), depth, 0.0002);
  EXPECT_NEAR(column(3, 1), 0.5 * depth, 0.0002);
  EXPECT_NEAR(column(0, 0), 0.0, 1e-9);
  EXPECT_NE(g.metadata().provenance.find("puddle.hf (5x4 samples)"), std::string::npos) << g.metadata().provenance;
}

TEST(VoxelizeSpill, PgmHeightFieldsAsciiAndBinary) {
  const auto ascii = temp_path("hf_ascii.pgm"), binary = temp_path("hf_binary.pgm");
  {
    std::ofstream out(ascii);
    out << "P2\n# comment\n3 2\n255\n0 255 51\n102 0 255\n";
  }
  {
    std::ofstream out(binary, std::ios::binary);
    out << "P5 3 2 65535\n";
    const unsigned short samples[] = {0, 65535, 13107, 26214, 0, 65535};
    for (unsigned short s : samples) out.put(char(s >> 8)).put(char(s & 0xff));
  }
  for (const auto& file : {ascii, binary}) {
    const HeightField f = load_height_field(file);
    ASSERT_EQ(f.nx, 3);
    ASSERT_EQ(f.nz, 2);
    EXPECT_FLOAT_EQ(f.at(1, 0), 1.f);
    EXPECT_FLOAT_EQ(f.at(2, 0), 0.2f);
    EXPECT_FLOAT_EQ(f.at(0, 1), 0.4f);
  }
}

// Unit, scale and provenance come back through load_concentration_grid, with the values.
TEST(VoxelizeFile, RoundTripKeepsMetadataAndValues) {
  const Bounds3 box{{0.f, 0.f, 0.f}, {0.02f, 0.01f, 0.015f}};
  const auto mesh_file = write_obj(make_box(box), "roundtrip_box.obj");
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.profile.concentration = 25.f;
  o.unit = "nM";
  o.grid_name = "chlorophyll_a";
  const auto path = temp_path("roundtrip.vdb");
  const VoxelizeReport r = voxelize_file(mesh_file, o, path);
  const VoxelGrid g = load_concentration_grid(path, "chlorophyll_a");
  EXPECT_EQ(g.metadata().unit, "nM");
  EXPECT_EQ(g.metadata().scale, 1.f);
  EXPECT_EQ(g.metadata().provenance, r.provenance);
  for (const char* part : {"chlorovdb voxelize", "roundtrip_box.obj", "(12 triangles)", "--mode solid",
                           "--voxel-size 0.001", "--concentration 25", "--unit nM"})
    EXPECT_NE(r.provenance.find(part), std::string::npos) << part << " not in " << r.provenance;
  // Faces on voxel centres: the face voxels are half covered, the inside holds C.
  EXPECT_EQ(g.voxel(10, 5, 7), 25.f);
  EXPECT_NEAR(g.voxel(0, 5, 7), 12.5f, 1e-4f);
  EXPECT_NEAR(g.voxel(20, 5, 7), 12.5f, 1e-4f);
  EXPECT_EQ(g.voxel(-1, 5, 7), 0.f);
  // A voxel centred on an edge is a quarter inside, on a corner an eighth. With 3 x 3 x 3 sub-voxels
  // the sub-voxels centred on the edges still count half: (2 + 3 · 1/2) / 9 = 0.25 + 1/36 on an edge,
  // (1 + 3 · 1/2 + 3 · 1/2 + 1/2) / 27 = 1/6 on a corner.
  EXPECT_NEAR(g.voxel(0, 0, 7), 25.f * (0.25f + 1.f / 36.f), 1e-3f);
  EXPECT_NEAR(g.voxel(20, 10, 15), 25.f / 6.f, 1e-3f);
  EXPECT_EQ(r.index_lo, (Coord{0, 0, 0}));
  EXPECT_EQ(r.index_hi, (Coord{20, 10, 15}));
  // Even with every edge on voxel centres (the worst case) the amount is within 0.3 %.
  EXPECT_NEAR(integral(g) / (25.0 * 0.02 * 0.01 * 0.015), 1.0, 0.003);
}

TEST(VoxelizeFile, InputTransformScalesMillimetres) {
  // A 20 mm cube given in millimetres, scaled to metres and moved.
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.world_from_input = Transform::translate({0.1f, 0.f, 0.f}) * Transform::scale(Vec3(0.001f));
  const VoxelizeReport r = voxelize_mesh(make_box({{0, 0, 0}, {20, 20, 20}}), o, temp_path("mm.vdb"));
  EXPECT_NEAR(r.filled_volume / 8e-6, 1.0, 0.002);
  EXPECT_EQ(r.index_lo[0], 100);
  EXPECT_EQ(r.index_hi[0], 120);
}
