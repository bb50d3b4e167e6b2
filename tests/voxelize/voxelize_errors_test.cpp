// Bad input is refused with an InputError that names the file and says what to do.
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>

#include "voxelize_test_util.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(VoxelizeErrors, OpenMeshInSolidModeSuggestsShell) {
  const auto file = write_obj(make_quad({0, 0, 0}, {0.1f, 0, 0}, {0, 0, 0.1f}), "open_quad.obj");
  const std::string e = error_of([&] {
    voxelize_file(file, options_with(VoxelizeMode::solid, Vec3(0.001f)), temp_path("never.vdb"));
  });
  EXPECT_TRUE(contains(e, file.string())) << e;
  EXPECT_TRUE(contains(e, "not closed")) << e;
  EXPECT_TRUE(contains(e, "--mode shell")) << e;
}

TEST(VoxelizeErrors, EmptyAndGarbageMeshFiles) {
  const auto empty = temp_path("empty.obj");
  std::ofstream(empty).close();
  const auto garbage = temp_path("garbage.ply");
  {
    std::ofstream out(garbage, std::ios::binary);
    for (int i = 0; i < 4096; ++i) out.put(char((i * 7919) ^ (i >> 3)));
  }
  const auto missing = temp_path("does_not_exist.obj");
  for (const auto& file : {empty, garbage, missing}) {
    const std::string e = error_of([&] {
      voxelize_file(file, options_with(VoxelizeMode::solid, Vec3(0.001f)), temp_path("never.vdb"));
    });
    EXPECT_TRUE(contains(e, file.string())) << e;
  }
  // An in-memory mesh without triangles.
  VoxelizeOptions shell = options_with(VoxelizeMode::shell, Vec3(0.001f));
  shell.thickness = 0.001f;
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(TriangleMesh{}, shell, temp_path("never.vdb")); }), "no triangles"));
}

TEST(VoxelizeErrors, BadVoxelSizes) {
  const TriangleMesh box = make_box({{0, 0, 0}, {0.01f, 0.01f, 0.01f}});
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const Vec3 h : {Vec3(0.f), Vec3(-0.001f), Vec3(nan), Vec3(inf), Vec3(0.001f, 0.f, 0.001f),
                       Vec3(0.001f, 0.001f, nan)}) {
    VoxelizeOptions o = options_with(VoxelizeMode::solid, h);
    o.source_name = "box.obj";
    const std::string e = error_of([&] { voxelize_mesh(box, o, temp_path("never.vdb")); });
    EXPECT_TRUE(contains(e, "box.obj: --voxel-size")) << e;
    EXPECT_TRUE(contains(e, "positive and finite")) << e;
  }
}

// OpenVDB cannot hold a transform for voxels of ~1e-5 m and less (finding F6):
// an InputError naming the flag and the way out, not openvdb::ArithmeticError.
TEST(VoxelizeErrors, VoxelsTooSmallForOpenVdbAreAnInputError) {
  const TriangleMesh box = make_box({{0, 0, 0}, {1e-4f, 1e-4f, 1e-4f}});
  for (const Vec3 h : {Vec3(1e-5f), Vec3(2e-5f, 5e-6f, 2e-5f), Vec3(1e-6f)}) {
    VoxelizeOptions o = options_with(VoxelizeMode::solid, h);
    o.source_name = "tiny.obj";
    const std::string e = error_of([&] { voxelize_mesh(box, o, temp_path("never.vdb")); });
    EXPECT_TRUE(contains(e, "tiny.obj: --voxel-size")) << e;
    EXPECT_TRUE(contains(e, "length_unit")) << e;
  }
}

TEST(VoxelizeErrors, ZeroVolumeBoundingBox) {
  // One triangle, front and back: closed, but flat.
  TriangleMesh flat;
  flat.positions = {{0, 0, 0}, {0.01f, 0, 0}, {0, 0.01f, 0}};
  flat.indices = {0, 1, 2, 0, 2, 1};
  ASSERT_TRUE(is_closed(flat));
  const std::string e = error_of([&] {
    voxelize_mesh(flat, options_with(VoxelizeMode::solid, Vec3(0.001f)), temp_path("never.vdb"));
  });
  EXPECT_TRUE(contains(e, "zero volume")) << e;
}

// A 1 m box at 10 µm: ~1e15 voxels. Refused from the estimate, before any allocation, at once.
TEST(VoxelizeErrors, VoxelCountOverTheLimitIsRefusedBeforeAllocating) {
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(1e-5f));
  o.source_name = "big_box.obj";
  const auto start = std::chrono::steady_clock::now();
  const std::string e = error_of([&] { voxelize_mesh(make_box({{0, 0, 0}, {1, 1, 1}}), o, temp_path("never.vdb")); });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0);
  EXPECT_TRUE(contains(e, "big_box.obj: --voxel-size = 1e-05")) << e;
  EXPECT_TRUE(contains(e, "needs about 1e+15 voxels")) << e;
  EXPECT_TRUE(contains(e, "more than 2^31 voxels")) << e;
  EXPECT_TRUE(contains(e, "available")) << e;
  EXPECT_FALSE(std::filesystem::exists(temp_path("never.vdb")));

  const VoxelEstimate est = estimate_voxels(make_box({{0, 0, 0}, {1, 1, 1}}), o,
                                            ProfileSampler(o.profile, {{0, 0, 0}, {1, 1, 1}}, "uM", "big_box.obj"));
  EXPECT_NEAR(est.body_voxels / 1e15, 1.0, 0.01);
  EXPECT_GT(est.available_bytes, 0);  // read from /proc/meminfo
}

// Under 2^31 voxels but over the memory allowed: refused with the estimate and the limit.
TEST(VoxelizeErrors, MemoryOverTheLimitIsRefused) {
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.0005f));
  o.memory_limit_bytes = 1 << 20;
  const std::string e = error_of([&] {
    voxelize_mesh(make_uv_sphere({0, 0, 0}, 0.05f, 32, 64), o, temp_path("never.vdb"));
  });
  EXPECT_TRUE(contains(e, "more memory than is available")) << e;
  EXPECT_TRUE(contains(e, "1 MB available (memory limit given)")) << e;
  EXPECT_TRUE(contains(e, "times larger would fit")) << e;
  EXPECT_GT(available_memory_bytes(), 0);
}

// A height field's memory is its tree's nodes, not its voxels: a one-column spike fills 8
// voxels of each 512-voxel leaf and 128 of each internal node it passes through. The spike
// (1e4 voxels, 7.7 MB with the nodes) was estimated at 0.1 MB and built; a broad puddle of
// twice the voxels (1.7 MB) fits the same 4 MB.
TEST(VoxelizeErrors, TallThinHeightFieldIsRefusedByItsTreeMemory) {
  VoxelizeOptions o = options_with(VoxelizeMode::spill, Vec3(0.001f));
  o.depth = 0.002f;
  o.memory_limit_bytes = 4 << 20;
  const auto spike = temp_path("spike.hf"), puddle = temp_path("broad.hf");
  std::ofstream(spike) << "1 5000 1\n0 0 0\n";
  {
    std::ofstream out(puddle);
    for (int j = 0; j < 101; ++j)
      for (int i = 0; i < 101; ++i) out << "1" << (i == 100 ? '\n' : ' ');
  }
  const std::string e = error_of([&] { voxelize_file(spike, o, temp_path("never.vdb")); });
  EXPECT_TRUE(contains(e, "more memory than is available")) << e;
  EXPECT_TRUE(contains(e, "spike.hf")) << e;
  o.depth = 0.001f;
  const VoxelizeReport r = voxelize_file(puddle, o, temp_path("broad.vdb"));
  EXPECT_GT(r.active_voxels, 20000);
  EXPECT_LT(r.estimate.bytes, 4 << 20);
}

// A mesh's memory is counted from the tree nodes its band touches: a needle one voxel wide
// (1 x 1 x 6000 voxels) needs 4 leaves and their internal nodes per 8 voxels of length. The
// band's area alone estimated it at 7 MB (a needle of 20 000 voxels: 22.9 MB estimated, 235 MB
// used); a sphere of 30 voxels' radius fits the same 32 MB.
TEST(VoxelizeErrors, ThinMeshIsRefusedByItsTreeMemory) {
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.memory_limit_bytes = 32 << 20;
  const std::string e = error_of([&] {
    voxelize_mesh(make_box({{0, 0, 0}, {0.001f, 0.001f, 6.f}}), o, temp_path("never.vdb"));
  });
  EXPECT_TRUE(contains(e, "more memory than is available")) << e;
  const VoxelizeReport r = voxelize_mesh(make_uv_sphere({0, 0, 0}, 0.03f, 32, 64), o, temp_path("sphere.vdb"));
  EXPECT_GT(r.active_voxels, 100000);
  EXPECT_LT(r.estimate.bytes, 32 << 20);
}

// Grids beyond ±2^24 voxels from the origin are refused by the renderer (float lookups), and
// the conversion's integer indices would overflow first (fuzz_mesh: a tetrahedron at x = 1e20
// with voxels a sixth of its size: UBSan, float-to-int overflow).
TEST(VoxelizeErrors, ObjectFarFromTheOriginIsRefused) {
  VoxelizeOptions o = options_with(VoxelizeMode::shell, Vec3(0.001f));
  o.thickness = 0.001f;
  const std::string far_mesh = error_of([&] {
    voxelize_mesh(make_quad({1e20f, 0, 0}, {1e15f, 0, 0}, {0, 0, 1e15f}), o, temp_path("never.vdb"));
  });
  EXPECT_TRUE(contains(far_mesh, "reaches 1e+23 voxels from the origin along x")) << far_mesh;
  // The band's reach counts: a box ending 2 voxels short of 2^24 is refused, one 100 short is
  // not (floats there are 2 voxels apart).
  o.mode = VoxelizeMode::solid;
  const float edge = float(1 << 24) * 0.001f;
  EXPECT_TRUE(contains(
      error_of([&] {
        voxelize_mesh(make_box({{0, 0, edge - 0.01f}, {0.004f, 0.004f, edge - 0.002f}}), o, temp_path("never.vdb"));
      }),
      "along z"));
  EXPECT_GT(voxelize_mesh(make_box({{0, 0, edge - 0.2f}, {0.004f, 0.004f, edge - 0.1f}}), o, temp_path("edge.vdb"))
                .active_voxels,
            0);
  VoxelizeOptions spill = options_with(VoxelizeMode::spill, Vec3(0.001f));
  spill.depth = 0.001f;
  spill.world_from_input = Transform::translate({0, 0, -1e20f});
  std::ofstream(temp_path("far.hf")) << "1 1\n1 1\n";
  const std::string far_field = error_of([&] { voxelize_file(temp_path("far.hf"), spill, temp_path("never.vdb")); });
  EXPECT_TRUE(contains(far_field, "from the origin along z")) << far_field;
}

TEST(VoxelizeErrors, ModeParameters) {
  const TriangleMesh quad = make_quad({0, 0, 0}, {0.1f, 0, 0}, {0, 0, -0.1f});
  EXPECT_TRUE(contains(error_of([&] {
                         voxelize_mesh(quad, options_with(VoxelizeMode::shell, Vec3(0.001f)), temp_path("n.vdb"));
                       }),
                       "--thickness"));
  EXPECT_TRUE(contains(error_of([&] {
                         voxelize_mesh(quad, options_with(VoxelizeMode::spill, Vec3(0.001f)), temp_path("n.vdb"));
                       }),
                       "--depth"));
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.unit = "ppm";
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(make_box({{0, 0, 0}, {0.01f, 0.01f, 0.01f}}), o, temp_path("n.vdb")); }),
                       "--unit = ppm"));
  // A vertical footprint cannot be extruded up.
  VoxelizeOptions up = options_with(VoxelizeMode::spill, Vec3(0.001f));
  up.depth = 0.001f;
  up.spill_direction = SpillDirection::up;
  EXPECT_TRUE(contains(error_of([&] {
                         voxelize_mesh(make_quad({0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}), up, temp_path("n.vdb"));
                       }),
                       "parallel"));
}

TEST(VoxelizeErrors, ProfileParameters) {
  const TriangleMesh box = make_box({{0, 0, 0}, {0.01f, 0.01f, 0.01f}});
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.profile.kind = ProfileKind::noise;
  o.profile.noise_amplitude = 1.5f;
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(box, o, temp_path("n.vdb")); }), "--noise-amplitude"));
  o.profile = {};
  o.profile.kind = ProfileKind::falloff;
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(box, o, temp_path("n.vdb")); }), "--falloff-length"));
  o.profile = {};
  o.profile.concentration = -1.f;
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(box, o, temp_path("n.vdb")); }), "--concentration = -1"));
  o.profile = {};
  o.profile.kind = ProfileKind::grid;
  o.profile.grid_file = temp_path("no_such_source.vdb");
  EXPECT_TRUE(contains(error_of([&] { voxelize_mesh(box, o, temp_path("n.vdb")); }), "no_such_source.vdb"));
}

TEST(VoxelizeErrors, BadHeightFields) {
  const auto ragged = temp_path("ragged.hf"), word = temp_path("word.txt"), zeros = temp_path("zeros.csv"),
             negative = temp_path("negative.hf");
  std::ofstream(ragged) << "1 2 3\n4 5\n";
  std::ofstream(word) << "1 2\n3 oops\n";
  std::ofstream(zeros) << "0,0\n0,0\n";
  std::ofstream(negative) << "1 2\n3 -4\n";
  EXPECT_TRUE(contains(error_of([&] { load_height_field(ragged); }), "ragged.hf: line 2"));
  EXPECT_TRUE(contains(error_of([&] { load_height_field(word); }), "word.txt: line 2, column 2 = oops: not a number"));
  EXPECT_TRUE(contains(error_of([&] { load_height_field(zeros); }), "holds no liquid"));
  EXPECT_TRUE(contains(error_of([&] { load_height_field(negative); }), ">= 0"));
  // A height field only makes spills.
  std::ofstream(temp_path("ok.hf")) << "1 1\n1 1\n";
  EXPECT_TRUE(contains(error_of([&] {
                         voxelize_file(temp_path("ok.hf"), options_with(VoxelizeMode::solid, Vec3(0.001f)),
                                       temp_path("n.vdb"));
                       }),
                       "--mode spill"));
}
