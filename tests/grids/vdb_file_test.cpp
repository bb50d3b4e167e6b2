// Round trips through real .vdb files. OpenVDB itself is included only to
// write grids of other value types (vec3s, double), which write_concentration_grid cannot make.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cstring>
#include <functional>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "core/error.h"
#include "core/rng.h"
#include "grids/vdb_file.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

std::filesystem::path temp_path(const std::string& name) {
  return test::scratch_dir("test_grids") / name;
}

DenseGrid test_grid(const std::string& name) {
  DenseGrid d({13, 7, 9});
  d.origin = {-4, 10, 2};
  d.metadata.name = name;
  d.metadata.unit = "uM";
  d.metadata.scale = 2.5f;
  d.metadata.provenance = "vdb_file_test";
  // Non-uniform scale, a rotation and a translation.
  d.world_from_index = Transform::translate({0.5f, -1.f, 2.f}) * Transform::rotate(30.f, {1, 2, 3}) *
                       Transform::scale({0.01f, 0.02f, 0.005f});
  Rng rng(test_seed(11), 0);
  for (float& v : d.values) v = rng.uniform() < 0.5f ? 0.f : rng.uniform();
  return d;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

}  // namespace

TEST(VdbFile, RoundTripKeepsValuesTransformAndMetadata) {
  const DenseGrid a = test_grid("chlorophyll_a"), b = test_grid("chlorophyll_b");
  const auto path = temp_path("roundtrip.vdb");
  const DenseGrid both[] = {a, b};
  write_concentration_grids(path, both);

  const VoxelGrid loaded = load_concentration_grid(path, "chlorophyll_a");
  const VoxelGrid direct = VoxelGrid::from_dense(a);
  EXPECT_EQ(loaded.metadata().unit, "uM");
  EXPECT_EQ(loaded.metadata().scale, 2.5f);
  EXPECT_EQ(loaded.metadata().provenance, "vdb_file_test");
  EXPECT_EQ(loaded.metadata().file, path.string());
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      EXPECT_NEAR(loaded.world_from_index().matrix()[i][j], a.world_from_index.matrix()[i][j], 1e-6f);
  Rng rng(test_seed(12), 0);
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p{-6.f + 17.f * rng.uniform(), 8.f + 11.f * rng.uniform(), 0.f + 13.f * rng.uniform()};
    // The file's leaf-aligned bounds shift the bricks, which may change the last bit.
    ASSERT_NEAR(loaded.trilinear(p), direct.trilinear(p), 1e-5f);
  }
  for (int z = -2; z < 13; ++z)
    for (int y = 8; y < 19; ++y)
      for (int x = -6; x < 11; ++x) ASSERT_EQ(loaded.voxel(x, y, z), direct.voxel(x, y, z));
  // World -> index of a voxel centre lands on its integer index.
  const Vec3 q = loaded.index_from_world().point(a.world_from_index.point({3, 12, 5}));
  EXPECT_NEAR(q.x, 3.f, 1e-3f);
  EXPECT_NEAR(q.y, 12.f, 1e-3f);
  EXPECT_NEAR(q.z, 5.f, 1e-3f);
}

TEST(VdbFile, MissingFileAndGridAreNamed) {
  EXPECT_NE(error_of([] { load_concentration_grid(temp_path("nope.vdb"), "x"); }).find("no such file"),
            std::string::npos);
  const auto path = temp_path("names.vdb");
  write_concentration_grid(path, test_grid("chlorophyll_a"));
  const std::string msg = error_of([&] { load_concentration_grid(path, "chlorophyl_a"); });
  EXPECT_NE(msg.find("names.vdb"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the file has: chlorophyll_a"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"chlorophyll_a\""), std::string::npos) << msg;
}

TEST(VdbFile, NotAVdbFileIsRefused) {
  const auto path = temp_path("garbage.vdb");
  { std::ofstream(path) << "not a vdb"; }
  EXPECT_NE(error_of([&] { load_concentration_grid(path, "x"); }).find("not a readable .vdb"), std::string::npos);
}

TEST(VdbFile, WrongTypeIsRefused) {
  openvdb::initialize();
  auto grid = openvdb::Vec3SGrid::create();
  grid->setName("velocity");
  grid->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  const auto path = temp_path("vec3.vdb");
  openvdb::io::File(path.string()).write({grid});
  const std::string msg = error_of([&] { load_concentration_grid(path, "velocity"); });
  EXPECT_NE(msg.find("velocity"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vec3s"), std::string::npos) << msg;
  EXPECT_EQ(inspect_vdb(path).grids.at(0).type, "vec3s");
}

// Double grids (common in public files) are read as float: values rounded,
// transform and metadata kept, and the conversion recorded.
TEST(VdbFile, DoubleGridIsConvertedToFloat) {
  openvdb::initialize();
  auto grid = openvdb::DoubleGrid::create(0.0);
  grid->setName("smoke");
  grid->setTransform(openvdb::math::Transform::createLinearTransform(0.05));
  grid->insertMeta("unit", openvdb::StringMetadata("nM"));
  const double third = 1.0 / 3.0;
  grid->tree().setValue(openvdb::Coord(1, 2, 3), third);
  grid->tree().setValue(openvdb::Coord(-9, 0, 17), 2.5);
  const auto path = temp_path("double.vdb");
  openvdb::io::File(path.string()).write({grid});
  const VoxelGrid g = load_concentration_grid(path, "smoke");
  EXPECT_EQ(g.metadata().converted_from, "double");
  EXPECT_EQ(g.metadata().unit, "nM");
  EXPECT_EQ(g.voxel(1, 2, 3), float(third));
  EXPECT_EQ(g.voxel(-9, 0, 17), 2.5f);
  EXPECT_EQ(g.voxel(0, 0, 0), 0.f);
  EXPECT_NEAR(g.world_from_index().point({2, 0, 0}).x, 0.1f, 1e-7f);
  EXPECT_EQ(g.index_lo()[0], -16);  // the leaf node holding (-9, 0, 17) starts at -16
  // A float grid records no conversion.
  const auto fpath = temp_path("float_for_double.vdb");
  write_concentration_grid(fpath, test_grid("chl"));
  EXPECT_EQ(load_concentration_grid(fpath, "chl").metadata().converted_from, "");
}

TEST(VdbFile, InvalidValuesAreRefusedOrClamped) {
  DenseGrid d = test_grid("chl");
  d.at(1, 1, 1) = std::nanf("");
  d.at(2, 1, 1) = -0.5f;
  const auto path = temp_path("invalid.vdb");
  write_concentration_grid(path, d);
  const std::string msg = error_of([&] { load_concentration_grid(path, "chl"); });
  EXPECT_NE(msg.find("invalid.vdb"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1 NaN, 0 infinite and 1 negative"), std::string::npos) << msg;
  const VoxelGrid g = load_concentration_grid(path, "chl", {.clamp_invalid = true});
  EXPECT_EQ(g.metadata().clamped_voxels, 2);
  EXPECT_EQ(g.voxel(d.origin[0] + 1, d.origin[1] + 1, d.origin[2] + 1), 0.f);

  const GridReport report = inspect_vdb(path);
  ASSERT_EQ(report.grids.size(), 1u);
  EXPECT_EQ(report.grids[0].invalid.nan, 1);
  EXPECT_EQ(report.grids[0].invalid.negative, 1);
}

TEST(VdbFile, InspectDescribesEveryGrid) {
  DenseGrid a({8, 8, 8}, 0.f);
  a.metadata.name = "blob";
  a.origin = {10, 20, 30};
  a.world_from_index = Transform::scale({0.5f, 0.25f, 2.f});
  a.at(2, 3, 4) = 7.f;
  a.at(5, 3, 4) = 1.f;
  const auto path = temp_path("inspect.vdb");
  write_concentration_grid(path, a);
  const GridReport r = inspect_vdb(path);
  ASSERT_EQ(r.grids.size(), 1u);
  const GridInfo& g = r.grids[0];
  EXPECT_EQ(g.name, "blob");
  EXPECT_EQ(g.type, "float");
  EXPECT_EQ(g.active_voxels, 2);
  ASSERT_TRUE(g.active_index_bounds);
  EXPECT_EQ(g.active_index_bounds->first, (Coord{12, 23, 34}));
  EXPECT_EQ(g.active_index_bounds->second, (Coord{15, 23, 34}));
  ASSERT_TRUE(g.value_range);
  EXPECT_EQ(g.value_range->first, 1.0);
  EXPECT_EQ(g.value_range->second, 7.0);
  EXPECT_NEAR(g.voxel_size.x, 0.5f, 1e-6f);
  EXPECT_NEAR(g.voxel_size.y, 0.25f, 1e-6f);
  EXPECT_NEAR(g.voxel_size.z, 2.f, 1e-6f);
  EXPECT_NEAR(g.active_world_bounds.lo.x, 11.5f * 0.5f, 1e-5f);
  EXPECT_NEAR(g.active_world_bounds.hi.z, 34.5f * 2.f, 1e-5f);
  EXPECT_GT(g.memory_bytes, 0);
  EXPECT_EQ(g.invalid.total(), 0);
  bool has_unit_scale = false;
  for (const auto& [k, v] : g.metadata) has_unit_scale |= k == "scale";
  EXPECT_TRUE(has_unit_scale);
}


namespace {

// Where a one-grid .vdb keeps its grid descriptor's three offsets (grid header, data
// blocks, end), following check_vdb_complete's walk: header, file metadata, grid
// count, the grid's name, type and instance-parent strings.
size_t descriptor_offsets_at(const std::string& bytes) {
  const auto u32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  size_t at = 8 + 4 + 8 + 1 + 36;  // magic, file version, library version, has-offsets flag, UUID
  const uint32_t entries = u32(at);
  at += 4;
  for (uint32_t i = 0; i < 3 * entries; ++i) at += 4 + u32(at);
  at += 4;                                             // grid count
  for (int i = 0; i < 3; ++i) at += 4 + u32(at);       // name, type, instance parent
  return at;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

// Corruptions inside a grid that the file-structure check alone let through: a file
// cut inside the grid's data blocks whose descriptor was rewritten to match, a grid
// metadata count turned into billions (OpenVDB looped on reading them), offsets out of
// order, a transform whose map name is garbled. Each is refused naming the file (and,
// where OpenVDB reads the grid, the grid) instead of an OpenVDB exception reaching the
// user as an internal error, a runaway loop or a silently wrong grid.
TEST(VdbFile, CorruptGridThatPassesTheStructureCheckIsRefused) {
  DenseGrid d({20, 12, 9});
  d.metadata.name = "chl";
  d.metadata.unit = "uM";
  Rng rng(test_seed(13), 0);
  for (float& v : d.values) v = rng.uniform() < 0.3f ? 0.f : rng.uniform();
  const auto whole = temp_path("corrupt_whole.vdb");
  write_concentration_grid(whole, d);
  const std::string bytes = read_bytes(whole);
  const size_t offsets_at = descriptor_offsets_at(bytes);
  int64_t pos[3];
  std::memcpy(pos, bytes.data() + offsets_at, sizeof(pos));
  ASSERT_EQ(uint64_t(pos[2]), bytes.size()) << "the test's walk of the file layout is off";
  ASSERT_LT(pos[0], pos[1]);
  EXPECT_NO_THROW(load_concentration_grid(whole, "chl"));

  const auto refused = [&](const std::string& corrupt, const std::string& expected) {
    const auto path = temp_path("corrupt.vdb");
    std::ofstream(path, std::ios::binary | std::ios::trunc) << corrupt;
    const std::string msg = error_of([&] { load_concentration_grid(path, "chl"); });
    EXPECT_NE(msg.find("corrupt.vdb"), std::string::npos) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << msg;
    EXPECT_NE(msg.find("corrupt"), std::string::npos) << msg;
  };
  const auto cut_with_matching_descriptor = [&](int64_t keep) {
    std::string cut = bytes.substr(0, size_t(keep));
    std::memcpy(cut.data() + offsets_at + 16, &keep, 8);  // the grid now "ends" where the file does
    return cut;
  };
  // Cut inside the data blocks, header intact: OpenVDB's own decompression error, now named.
  for (const int64_t keep : {pos[1] + 7, (pos[1] + pos[2]) / 2})
    refused(cut_with_matching_descriptor(keep), "grid = chl: cannot be read");
  // Cut inside the grid's header: the descriptor's end comes before its data blocks.
  refused(cut_with_matching_descriptor((pos[0] + pos[1]) / 2), "offsets are out of order");
  // The grid's metadata count (after its 4-byte compression flags) made huge.
  std::string count = bytes;
  count[size_t(pos[0]) + 4 + 3] = char(0x7f);
  refused(count, "runs past the grid's header");
  // The transform's map type name garbled: OpenVDB's KeyError, named.
  std::string map = bytes;
  const size_t name_at = map.find("UniformScaleMap");
  ASSERT_NE(name_at, std::string::npos);
  map[name_at + 3] = 'X';
  refused(map, "grid = chl: cannot be read");
}
