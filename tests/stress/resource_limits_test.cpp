// Resource limits (issue 7): inputs that would need more memory than the machine
// has must be refused, with an estimate, before anything large is allocated.
//
// Voxelize (voxelize.h check_estimate), the grid loader's brick table, the film,
// its spectral bins and the scene loader all refuse with the estimate and
// MemAvailable (core/memory.h) before allocating.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <string>

#include "core/error.h"
#include "film/film.h"
#include "grids/vdb_file.h"
#include "scene/scene_loader.h"
#include "sparse_vdb_writer.h"
#include "stress_util.h"
#ifdef CHLOROVDB_HAVE_VOXELIZE
#include "geometry/mesh.h"
#include "voxelize/voxelize.h"
#endif

using namespace chlorovdb;
using namespace chlorovdb::stress;

namespace {

// Peak resident memory of this process so far (VmHWM), bytes.
int64_t peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;
  return 0;
}

int64_t mem_available_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("MemAvailable:", 0) == 0) return std::stoll(line.substr(13)) * 1024;
  return 0;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

constexpr int64_t kAllowedGrowth = 256 << 20;  // "before allocating": the refusal itself may cost this much

}  // namespace

#ifdef CHLOROVDB_HAVE_VOXELIZE
// A 1 m cube at 1 µm voxels: 1e18 voxels. Refused from the estimate (2^31 cap
// or MemAvailable), quickly, with the estimate in the message, without growing.
TEST(ResourceLimits, VoxelizeRefusesBeforeAllocating) {
  const int64_t before = peak_rss_bytes();
  const auto t0 = std::chrono::steady_clock::now();
  VoxelizeOptions o;
  o.voxel_size = Vec3(1e-6f);
  o.source_name = "unit cube";
  Bounds3 box;
  box.lo = Vec3(0.f);
  box.hi = Vec3(1.f);
  try {
    voxelize_mesh(make_box(box), o, scratch_dir() / "never_written.vdb");
    FAIL() << "a 1e18-voxel conversion was not refused";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "unit cube")) << m;
    EXPECT_TRUE(contains(m, "voxel")) << m;
    EXPECT_TRUE(contains(m, "available")) << m;  // states the machine's memory next to the estimate
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0 * time_scale());
  EXPECT_LT(peak_rss_bytes() - before, kAllowedGrowth);
  EXPECT_FALSE(std::filesystem::exists(scratch_dir() / "never_written.vdb"));
}

// Just under the 2^31 voxel cap but above this machine's memory (the MemAvailable branch): a
// memory_limit of 1/1000 of MemAvailable stands in for a smaller machine.
TEST(ResourceLimits, VoxelizeRefusesAboveMemAvailable) {
  const int64_t available = mem_available_bytes();
  ASSERT_GT(available, 0);
  VoxelizeOptions o;
  o.voxel_size = Vec3(2e-3f);  // a 1 m cube: 1.25e8 voxels, under the cap
  o.memory_limit_bytes = available / 1000;
  o.source_name = "unit cube";
  Bounds3 box;
  box.lo = Vec3(0.f);
  box.hi = Vec3(1.f);
  const int64_t before = peak_rss_bytes();
  try {
    voxelize_mesh(make_box(box), o, scratch_dir() / "never_written2.vdb");
    FAIL() << "not refused";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "more memory than is available")) << e.what();
  }
  EXPECT_LT(peak_rss_bytes() - before, kAllowedGrowth);
}
#endif

// ---------------------------------------------------------------------------
// Refused before allocating, with the estimate and MemAvailable.
// ---------------------------------------------------------------------------

// load_concentration_grid allocates one table entry per 8^3 brick of the active
// bounding box (VoxelGrid::from_bricks), so two active voxels 2^27 apart ask for
// ~2^72 entries: today size_t overflow in the brick count, then std::bad_alloc.
// Wanted: an InputError naming the file, the grid, the estimated bytes and MemAvailable.
TEST(ResourceLimits, SparseGridWithHugeBoundsIsRefusedWithEstimate) {
  const auto path = scratch_dir() / "two_far_voxels.vdb";
  write_sparse_grid(path, {{{0, 0, 0}, 1.f}, {{1 << 27, 1 << 27, 1 << 27}, 1.f}}, 1e-3);
  const int64_t before = peak_rss_bytes();
  try {
    load_concentration_grid(path, "density");
    FAIL() << "a grid spanning 2^27 voxels per axis was loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "two_far_voxels.vdb")) << e.what();
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  }
  EXPECT_LT(peak_rss_bytes() - before, kAllowedGrowth);
}

// The same with bounds whose brick table alone would need 256 GB (no overflow
// this time): 2^15 voxels apart per axis -> 2^36 bricks x 4 bytes.
TEST(ResourceLimits, SparseGridNeedingMoreThanMemAvailableIsRefused) {
  const auto path = scratch_dir() / "two_voxels_256gb.vdb";
  write_sparse_grid(path, {{{0, 0, 0}, 1.f}, {{1 << 15, 1 << 15, 1 << 15}, 1.f}}, 1e-3);
  try {
    load_concentration_grid(path, "density");
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  }
}

// Film allocates 3 doubles per pixel per layer (plus bins doubles for spectral
// bins), and render() holds a second, per-pass Film of the same size: a
// 65536 x 65536 render with the 3 layers needs 2 x 309 GB. Wanted: refused with
// the estimate and MemAvailable before allocating (at load_scene, where the
// resolution is known, or in the Film constructor).
TEST(ResourceLimits, FilmLargerThanMemoryIsRefusedWithEstimate) {
  const int64_t before = peak_rss_bytes();
  try {
    Film film(65536, 65536, {"total", "fluorescence", "nonfluorescence"}, ColorSpace::sRGB);
    FAIL() << "a 309 GB film was allocated";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  }
  EXPECT_LT(peak_rss_bytes() - before, kAllowedGrowth);
}

TEST(ResourceLimits, SpectralBinsLargerThanMemoryAreRefused) {
  Film film(8192, 8192, {"total"}, ColorSpace::sRGB);  // 1.6 GB
  try {
    film.enable_spectral(kLambdaMin, kLambdaMax, 4096);  // + 2.2 TB
    FAIL() << "2.2 TB of spectral bins allocated";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  }
}

TEST(ResourceLimits, SceneWithUnrenderableResolutionIsRefusedAtLoad) {
  const auto path = write_scene("huge_resolution", R"({
    "render": {"resolution": [65536, 65536], "spectral_bins": 4096},
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}
  })");
  try {
    load_scene(path);
    FAIL() << "accepted a scene whose film needs ~140 TB";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "resolution")) << e.what();
    EXPECT_TRUE(contains(e.what(), "available")) << e.what();
  }
}

// ---------------------------------------------------------------------------
// Index arithmetic at the ends of the int range (not memory, but the same code:
// VoxelGrid::from_bricks computes brick counts as index_hi + 2 - brick_base + 7).
// Wanted: a clean InputError (or a working grid), never signed overflow.
// ---------------------------------------------------------------------------
TEST(ResourceLimits, GridNearIntMaxIsRefusedOrWorks) {
  DenseGrid g({8, 8, 8}, 1.f);
  g.origin = {2147483647 - 7, 0, 0};  // last voxel at INT_MAX
  g.metadata.name = "edge";
  try {
    const VoxelGrid grid = VoxelGrid::from_dense(g);
    EXPECT_EQ(grid.voxel(2147483647, 0, 0), 1.f);
    EXPECT_EQ(grid.trilinear(Vec3(2147483520.f, 1.f, 1.f)), 1.f);
  } catch (const InputError&) {
    // Refusing such indices is fine.
  }
}

TEST(ResourceLimits, GridNearIntMinIsRefusedOrWorks) {
  DenseGrid g({8, 8, 8}, 1.f);
  g.origin = {-2147483647 - 1, 0, 0};  // first voxel at INT_MIN
  g.metadata.name = "edge";
  try {
    const VoxelGrid grid = VoxelGrid::from_dense(g);
    EXPECT_EQ(grid.voxel(-2147483647 - 1, 0, 0), 1.f);
  } catch (const InputError&) {
  }
}
