#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "grids/voxel_grid.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

DenseGrid random_grid(Coord dims, Coord origin, uint64_t seed) {
  DenseGrid d(dims);
  d.origin = origin;
  Rng rng(test_seed(seed), 0);
  for (float& v : d.values) v = rng.uniform() < 0.3f ? 0.f : rng.uniform() * 10.f;
  return d;
}

// Value of voxel (x,y,z) as a lookup must see it: background outside the box.
float reference_voxel(const DenseGrid& d, int x, int y, int z) {
  const int i = x - d.origin[0], j = y - d.origin[1], k = z - d.origin[2];
  if (i < 0 || j < 0 || k < 0 || i >= d.dims[0] || j >= d.dims[1] || k >= d.dims[2]) return d.background;
  return d.at(i, j, k);
}

float reference_trilinear(const DenseGrid& d, const Vec3& p) {
  const int x = int(std::floor(p.x)), y = int(std::floor(p.y)), z = int(std::floor(p.z));
  const float wx = p.x - float(x), wy = p.y - float(y), wz = p.z - float(z);
  float r = 0.f;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
    const float w = (dx ? wx : 1 - wx) * (dy ? wy : 1 - wy) * (dz ? wz : 1 - wz);
    r += w * reference_voxel(d, x + dx, y + dy, z + dz);
  }
  return r;
}

Vec3 random_point_around(const DenseGrid& d, Rng& rng) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) p[a] = float(d.origin[a]) - 3.f + rng.uniform() * float(d.dims[a] + 6);
  return p;
}

}  // namespace

TEST(VoxelGrid, TrilinearMatchesBruteForceAcrossBrickBorders) {
  const DenseGrid d = random_grid({21, 13, 19}, {-5, 3, -12}, 1);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  Rng rng(test_seed(2), 0);
  // The grid chains lerps from brick-relative coordinates, the reference sums weight
  // products: both round, by a few ulps of the largest value per step (a seed sweep met
  // 1.0e-5 at values near 10, ~8 eps x 10). A wrong voxel or weight is off by O(1).
  const float max_value = *std::max_element(d.values.begin(), d.values.end());
  const float tolerance = 32.f * std::numeric_limits<float>::epsilon() * max_value;
  for (int i = 0; i < 200000; ++i) {
    const Vec3 p = random_point_around(d, rng);
    ASSERT_NEAR(g.trilinear(p), reference_trilinear(d, p), tolerance) << p.x << " " << p.y << " " << p.z;
  }
}

TEST(VoxelGrid, NearestReturnsTheClosestVoxel) {
  const DenseGrid d = random_grid({17, 9, 10}, {8, -8, 0}, 3);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  Rng rng(test_seed(4), 0);
  for (int i = 0; i < 100000; ++i) {
    const Vec3 p = random_point_around(d, rng);
    const float ref =
        reference_voxel(d, int(std::floor(p.x + 0.5f)), int(std::floor(p.y + 0.5f)), int(std::floor(p.z + 0.5f)));
    ASSERT_EQ(g.nearest(p), ref);
  }
}

TEST(VoxelGrid, LinearFieldIsReproducedExactly) {
  DenseGrid d({12, 12, 12});
  for (int z = 0; z < 12; ++z)
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 12; ++x) d.at(x, y, z) = 1.f + 0.5f * float(x) + 0.25f * float(y) + 2.f * float(z);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  Rng rng(test_seed(5), 0);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 p{rng.uniform() * 11.f, rng.uniform() * 11.f, rng.uniform() * 11.f};
    ASSERT_NEAR(g.trilinear(p), 1.f + 0.5f * p.x + 0.25f * p.y + 2.f * p.z, 2e-5f);
  }
}

TEST(VoxelGrid, NonZeroBackgroundFillsTheOutside) {
  DenseGrid d({4, 4, 4}, 1.f);
  d.background = 0.25f;
  const VoxelGrid g = VoxelGrid::from_dense(d);
  EXPECT_EQ(g.trilinear({-10.f, 2.f, 2.f}), 0.25f);
  EXPECT_EQ(g.trilinear({1e30f, 2.f, 2.f}), 0.25f);
  EXPECT_NEAR(g.trilinear({-0.5f, 1.f, 1.f}), 0.625f, 1e-6f);  // halfway between the background and the edge voxel
  EXPECT_EQ(g.min_value(), 0.25f);
  EXPECT_EQ(g.max_value(), 1.f);
}

TEST(VoxelGrid, BackgroundBricksAreShared) {
  DenseGrid d({64, 64, 64});
  d.at(40, 40, 40) = 3.f;
  const VoxelGrid g = VoxelGrid::from_dense(d);
  // Voxel 40 sits in brick [40, 48) and in the aprons of the bricks ending at 40 on each axis.
  EXPECT_EQ(g.allocated_bricks(), 8u);
  EXPECT_EQ(g.voxel(40, 40, 40), 3.f);
  EXPECT_EQ(g.trilinear({40.f, 40.f, 40.f}), 3.f);
  EXPECT_NEAR(g.trilinear({39.5f, 40.f, 40.f}), 1.5f, 1e-6f);
  EXPECT_LT(g.memory_bytes(), size_t(64 * 64 * 64 * 4) / 20);
}

TEST(VoxelGrid, MinMaxAndMeanOverBoxes) {
  const DenseGrid d = random_grid({20, 20, 20}, {-3, -3, -3}, 6);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  Rng rng(test_seed(7), 0);
  for (int i = 0; i < 300; ++i) {
    Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = -6 + int(rng.uniform() * 26.f);
      hi[a] = lo[a] + int(rng.uniform() * 10.f);
    }
    float mn = 1e30f, mx = -1e30f;
    double sum = 0.0;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          mn = std::min(mn, reference_voxel(d, x, y, z));
          mx = std::max(mx, reference_voxel(d, x, y, z));
          sum += reference_voxel(d, x, y, z);
        }
    const auto [gmn, gmx] = g.min_max(lo, hi);
    ASSERT_EQ(gmn, mn);
    ASSERT_EQ(gmx, mx);
    const double count = double(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    ASSERT_NEAR(g.mean(lo, hi), sum / count, 1e-6 * std::max(1.0, std::abs(sum / count)));
  }
}

TEST(VoxelGrid, CopyBlockMatchesEachVoxel) {
  // Boxes across brick borders and past the stored voxels, with a non-zero background.
  DenseGrid d = random_grid({21, 18, 19}, {-5, 2, -9}, 8);
  d.background = 0.5f;
  const VoxelGrid g = VoxelGrid::from_dense(d);
  Rng rng(test_seed(9), 0);
  for (int i = 0; i < 300; ++i) {
    Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = d.origin[a] - 4 + int(rng.uniform() * float(d.dims[a] + 4));
      hi[a] = lo[a] + int(rng.uniform() * 18.f);
    }
    std::vector<float> block(size_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1), -1.f);
    g.copy_block(lo, hi, block.data());
    size_t k = 0;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x, ++k) ASSERT_EQ(block[k], reference_voxel(d, x, y, z)) << x << " " << y << " " << z;
  }
}

TEST(VoxelGrid, InvalidValuesAreRefusedWithCounts) {
  DenseGrid d({10, 10, 10}, 1.f);
  d.metadata.name = "chl";
  d.at(1, 2, 3) = std::nanf("");
  d.at(2, 2, 3) = INFINITY;
  d.at(3, 2, 3) = -1.f;
  d.at(4, 2, 3) = -2.f;
  try {
    VoxelGrid::from_dense(d);
    FAIL() << "invalid values were accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("chl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 NaN, 1 infinite and 2 negative"), std::string::npos) << msg;
  }
  const VoxelGrid g = VoxelGrid::from_dense(d, /*clamp_invalid=*/true);
  EXPECT_EQ(g.metadata().clamped_voxels, 4);
  EXPECT_EQ(g.voxel(1, 2, 3), 0.f);
  EXPECT_EQ(g.voxel(4, 2, 3), 0.f);
  EXPECT_EQ(g.voxel(5, 2, 3), 1.f);
}

TEST(VoxelGrid, WorldBoundsFollowNonUniformScale) {
  DenseGrid d({10, 20, 5}, 1.f);
  d.world_from_index = Transform::translate({1, 2, 3}) * Transform::scale({0.1f, 0.01f, 2.f});
  const VoxelGrid g = VoxelGrid::from_dense(d);
  const Bounds3 b = g.world_bounds(Interpolation::nearest);
  EXPECT_NEAR(b.lo.x, 1.f - 0.05f, 1e-5f);
  EXPECT_NEAR(b.hi.x, 1.f + 0.95f, 1e-5f);
  EXPECT_NEAR(b.lo.y, 2.f - 0.005f, 1e-5f);
  EXPECT_NEAR(b.hi.y, 2.f + 0.195f, 1e-5f);
  EXPECT_NEAR(b.lo.z, 3.f - 1.f, 1e-5f);
  EXPECT_NEAR(b.hi.z, 3.f + 9.f, 1e-5f);
  // Trilinear lookups fade each voxel out over a whole voxel.
  const Bounds3 t = g.world_bounds(Interpolation::trilinear);
  EXPECT_NEAR(t.lo.x, 1.f - 0.1f, 1e-5f);
  EXPECT_NEAR(t.hi.x, 1.f + 1.0f, 1e-5f);
  EXPECT_NEAR(t.lo.z, 3.f - 2.f, 1e-5f);
  EXPECT_NEAR(t.hi.z, 3.f + 10.f, 1e-5f);
}
