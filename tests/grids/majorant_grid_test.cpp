#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "grids/majorant_grid.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Mostly empty, with isolated spikes and a few dense blocks: the features a
// majorant built without the full stencil (or its margin) would miss.
DenseGrid spiky_grid(Coord dims, uint64_t seed) {
  DenseGrid d(dims);
  Rng rng(test_seed(seed), 0);
  for (float& v : d.values)
    if (rng.uniform() < 0.01f) v = 100.f * rng.uniform();
  for (int b = 0; b < 3; ++b) {
    const int x0 = int(rng.uniform() * float(dims[0] - 6)), y0 = int(rng.uniform() * float(dims[1] - 6)),
              z0 = int(rng.uniform() * float(dims[2] - 6));
    for (int z = z0; z < z0 + 5; ++z)
      for (int y = y0; y < y0 + 5; ++y)
        for (int x = x0; x < x0 + 5; ++x) d.at(x, y, z) = 5.f + rng.uniform();
  }
  return d;
}

Ray random_ray(const Bounds3& box, Rng& rng, bool axis_parallel) {
  const Vec3 size = box.diagonal();
  Vec3 o;
  for (int a = 0; a < 3; ++a) o[a] = box.lo[a] - 0.5f * size[a] + 2.f * size[a] * rng.uniform();
  Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
  if (axis_parallel) {
    const int a = int(rng.uniform() * 3.f);
    d = Vec3(0.f);
    d[a] = rng.uniform() < 0.5f ? -1.f : 1.f;
  }
  return {o, d * (0.5f + rng.uniform())};  // not unit length: t is the ray's own parameter
}

std::vector<MajorantSegment> collect(const MajorantGrid& m, const Ray& r, float t_max) {
  std::vector<MajorantSegment> s;
  auto it = m.segments(r, t_max);
  while (auto seg = it.next()) s.push_back(*seg);
  return s;
}

}  // namespace

TEST(MajorantGrid, SegmentsTileTheRayExactly) {
  const VoxelGrid g = VoxelGrid::from_dense(spiky_grid({40, 33, 27}, 1));
  const VoxelGrid* channels[] = {&g};
  const MajorantGrid m(channels, 8, Interpolation::trilinear);
  Rng rng(test_seed(2), 0);
  for (int i = 0; i < 5000; ++i) {
    const Ray r = random_ray(g.index_bounds(Interpolation::trilinear), rng, i % 4 == 0);
    const float t_max = 200.f * rng.uniform();
    const auto segs = collect(m, r, t_max);
    ASSERT_FALSE(segs.empty());
    EXPECT_EQ(segs.front().t_min, 0.f);
    EXPECT_EQ(segs.back().t_max, t_max);
    for (size_t s = 0; s < segs.size(); ++s) {
      EXPECT_LE(segs[s].t_min, segs[s].t_max);
      if (s > 0) {
        EXPECT_EQ(segs[s].t_min, segs[s - 1].t_max);
      }
    }
  }
}

TEST(MajorantGrid, NoLookupExceedsItsSegmentBounds) {
  const DenseGrid d0 = spiky_grid({37, 29, 41}, 3);
  // A second channel with its own (rotated, non-uniformly scaled) index space.
  DenseGrid d1 = spiky_grid({20, 25, 15}, 4);
  d1.world_from_index = Transform::translate({3.f, -2.f, 5.f}) * Transform::rotate(37.f, {1, 1, 0}) *
                        Transform::scale({1.7f, 0.8f, 2.3f});
  const VoxelGrid g0 = VoxelGrid::from_dense(d0), g1 = VoxelGrid::from_dense(d1);
  const Transform g1_from_g0 = g1.index_from_world() * g0.world_from_index();
  const VoxelGrid* channels[] = {&g0, &g1};
  Rng rng(test_seed(5), 0);
  int64_t checked = 0;
  for (Interpolation mode : {Interpolation::trilinear, Interpolation::nearest})
    for (int voxels_per_cell : {1, 3, 8, 16}) {
      const MajorantGrid m(channels, voxels_per_cell, mode);
      for (int i = 0; i < 3000; ++i) {
        const Ray r = random_ray(m.index_bounds(), rng, i % 5 == 0);
        for (const MajorantSegment& s : collect(m, r, 150.f)) {
          for (int k = 0; k < 24; ++k) {
            // The end points too: lookups there belong to both neighbours.
            const float u = k == 0 ? 0.f : (k == 1 ? 1.f : rng.uniform());
            const Vec3 p = r.at(s.t_min + u * (s.t_max - s.t_min));
            const float v0 = g0.lookup(p, mode), v1 = g1.lookup(g1_from_g0.point(p), mode);
            const bool nearest = mode == Interpolation::nearest;
            ASSERT_LE(v0, s.c_max[0]) << "cell size " << voxels_per_cell << ", nearest " << nearest;
            ASSERT_GE(v0, s.c_min[0]) << "cell size " << voxels_per_cell << ", nearest " << nearest;
            ASSERT_LE(v1, s.c_max[1]) << "cell size " << voxels_per_cell << ", nearest " << nearest;
            ASSERT_GE(v1, s.c_min[1]) << "cell size " << voxels_per_cell << ", nearest " << nearest;
            ++checked;
          }
        }
      }
    }
  EXPECT_GT(checked, 1000000);
}

TEST(MajorantGrid, TrilinearBoundsWeighTheOuterVoxelsByThreeQuarters) {
  // A ramp along x, value = voxel index + 1. A lookup within a quarter voxel of a cell
  // reaches a quarter voxel short of its outer voxels' centres, so a trilinear one
  // returns at most the last own value + 3/4 and at least the first - 3/4, while a
  // nearest one returns the outer voxels' values themselves.
  DenseGrid d({16, 16, 16});
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) d.at(x, y, z) = float(x + 1);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  const VoxelGrid* channels[] = {&g};
  const MajorantGrid tri(channels, 4, Interpolation::trilinear), near(channels, 4, Interpolation::nearest);
  // A cell whose own voxels and outer layer lie inside the grid on every axis.
  const Coord cell{2, 2, 2};
  Coord own_lo;
  for (int a = 0; a < 3; ++a) own_lo[a] = int(std::ceil(tri.index_bounds().lo[a])) + 4 * cell[a];
  for (int a = 0; a < 3; ++a) ASSERT_TRUE(own_lo[a] >= 1 && own_lo[a] + 4 <= 15) << "axis " << a;
  const float first = float(own_lo[0] + 1), last = first + 3.f;
  EXPECT_FLOAT_EQ(tri.cell_max(cell, 0), last + 0.75f);
  EXPECT_FLOAT_EQ(tri.cell_min(cell, 0), first - 0.75f);
  EXPECT_EQ(near.cell_max(cell, 0), last + 1.f);
  EXPECT_EQ(near.cell_min(cell, 0), first - 1.f);
}

TEST(MajorantGrid, JumpsOverEmptySpaceKeepTheBoundsAndTheTiling) {
  // A large, nearly empty grid: most cells are far from any data, so the DDA
  // crosses them in jumps. Every lookup must still respect its segment.
  DenseGrid d({150, 120, 130});
  Rng rng(test_seed(7), 0);
  for (int b = 0; b < 12; ++b) {
    const int x0 = int(rng.uniform() * 145.f), y0 = int(rng.uniform() * 115.f), z0 = int(rng.uniform() * 125.f);
    for (int z = z0; z < z0 + 4; ++z)
      for (int y = y0; y < y0 + 4; ++y)
        for (int x = x0; x < x0 + 4; ++x) d.at(x, y, z) = 1.f + rng.uniform();
  }
  const VoxelGrid g = VoxelGrid::from_dense(d);
  const VoxelGrid* channels[] = {&g};
  int64_t nonzero = 0;
  for (int voxels_per_cell : {1, 4, 8}) {
    const MajorantGrid m(channels, voxels_per_cell, Interpolation::trilinear);
    for (int i = 0; i < 3000; ++i) {
      const Ray r = random_ray(m.index_bounds(), rng, i % 5 == 0);
      const auto segs = collect(m, r, 600.f);
      ASSERT_EQ(segs.front().t_min, 0.f);
      ASSERT_EQ(segs.back().t_max, 600.f);
      for (size_t s = 0; s < segs.size(); ++s) {
        if (s > 0) {
          ASSERT_EQ(segs[s].t_min, segs[s - 1].t_max);
        }
        for (int k = 0; k < 16; ++k) {
          const float u = k == 0 ? 0.f : (k == 1 ? 1.f : rng.uniform());
          const float v = g.trilinear(r.at(segs[s].t_min + u * (segs[s].t_max - segs[s].t_min)));
          ASSERT_LE(v, segs[s].c_max[0]) << "cell size " << voxels_per_cell;
          nonzero += v > 0.f;
        }
      }
    }
  }
  EXPECT_GT(nonzero, 300);  // the rays do meet the blobs
}

TEST(MajorantGrid, EmptyRunsComeOutAsOneSegment) {
  DenseGrid d({128, 16, 16});
  for (int x : {20, 100}) d.at(x, 8, 8) = 1.f;  // two isolated voxels along one line
  const VoxelGrid g = VoxelGrid::from_dense(d);
  const VoxelGrid* channels[] = {&g};
  const MajorantGrid m(channels, 4, Interpolation::trilinear);
  const auto segs = collect(m, Ray{{-50.f, 8.f, 8.f}, {1.f, 0.f, 0.f}}, 300.f);
  // empty | cells around x = 20 | empty | cells around x = 100 | empty
  int empty_runs = 0;
  for (size_t s = 0; s < segs.size(); ++s) {
    const bool empty = segs[s].c_max[0] == 0.f;
    if (empty) ++empty_runs;
    if (s > 0) {
      EXPECT_FALSE(empty && segs[s - 1].c_max[0] == 0.f) << "two empty segments in a row";
    }
  }
  EXPECT_EQ(empty_runs, 3);
  EXPECT_LE(segs.size(), 3u + 2u * 3u);  // the stencil of one voxel reaches at most 3 cells of 4
}

TEST(MajorantGrid, RayOnCellBoundaryPlanesAndMissingRays) {
  const VoxelGrid g = VoxelGrid::from_dense(spiky_grid({32, 32, 32}, 6));
  const VoxelGrid* channels[] = {&g};
  const MajorantGrid m(channels, 8, Interpolation::trilinear);
  const Bounds3 b = m.index_bounds();
  // Exactly on the planes between cells, along each axis and both directions.
  for (int a = 0; a < 3; ++a)
    for (float dir : {-1.f, 1.f}) {
      Vec3 o = b.lo + Vec3(8.f, 8.f, 8.f), d(0.f);
      o[a] = dir > 0 ? b.lo[a] - 5.f : b.hi[a] + 5.f;
      d[a] = dir;
      const auto segs = collect(m, {o, d}, 100.f);
      EXPECT_EQ(segs.back().t_max, 100.f);
      for (size_t s = 1; s < segs.size(); ++s) {
        EXPECT_EQ(segs[s].t_min, segs[s - 1].t_max);
      }
    }
  // A ray that misses the grid: one empty segment.
  const auto miss = collect(m, {b.hi + Vec3(10.f), {1.f, 0.f, 0.f}}, 50.f);
  ASSERT_EQ(miss.size(), 1u);
  EXPECT_EQ(miss[0].t_max, 50.f);
  EXPECT_EQ(miss[0].c_max[0], 0.f);
}

TEST(MajorantGrid, WithoutChannelsTheRayIsOneSegment) {
  const MajorantGrid m;
  const auto segs = collect(m, {{0, 0, 0}, {1, 0, 0}}, 7.f);
  ASSERT_EQ(segs.size(), 1u);
  EXPECT_EQ(segs[0].t_min, 0.f);
  EXPECT_EQ(segs[0].t_max, 7.f);
}

TEST(MajorantGrid, CellMeansAreTheMeansOfTheirOwnVoxels) {
  // The mean predicts what a ray meets in a cell (the predicted roulette in
  // transmittance.cpp): it averages the voxels whose centres lie in the cell, and so
  // lies between the cell's bounds; segments point at it.
  const DenseGrid d = spiky_grid({40, 33, 27}, 5);
  const VoxelGrid g = VoxelGrid::from_dense(d);
  const VoxelGrid* channels[] = {&g};
  for (int voxels_per_cell : {1, 3, 8}) {
    const MajorantGrid m(channels, voxels_per_cell, Interpolation::trilinear);
    const Vec3 origin = m.index_bounds().lo;  // cell faces on voxel faces: origin is a half-integer
    const Coord res = m.resolution();
    for (int z = 0; z < res[2]; ++z)
      for (int y = 0; y < res[1]; ++y)
        for (int x = 0; x < res[0]; ++x) {
          const Coord cell{x, y, z};
          double sum = 0.0;
          Coord lo;
          for (int a = 0; a < 3; ++a) lo[a] = int(std::ceil(origin[a])) + cell[a] * voxels_per_cell;
          for (int k = 0; k < voxels_per_cell; ++k)
            for (int j = 0; j < voxels_per_cell; ++j)
              for (int i = 0; i < voxels_per_cell; ++i) sum += g.voxel(lo[0] + i, lo[1] + j, lo[2] + k);
          const double mean = sum / double(voxels_per_cell * voxels_per_cell * voxels_per_cell);
          const float c_mean = m.cell_mean(cell, 0);
          ASSERT_NEAR(c_mean, mean, 1e-5 * std::max(1.0, mean)) << "cell size " << voxels_per_cell;
          ASSERT_LE(m.cell_min(cell, 0), c_mean);
          ASSERT_GE(m.cell_max(cell, 0), c_mean);
        }
    Rng rng(test_seed(6), 0);
    for (int i = 0; i < 200; ++i)
      for (const MajorantSegment& s : collect(m, random_ray(g.index_bounds(Interpolation::trilinear), rng, false), 100.f)) {
        ASSERT_LE(*s.c_min, *s.c_mean);
        ASSERT_GE(*s.c_max, *s.c_mean);
      }
  }
}
