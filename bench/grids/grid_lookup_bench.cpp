// Lookups per second of three read-only structures over the same 256^3 fields:
// a dense array (the floor no sparse structure beats), VoxelGrid (bricks with
// an apron) and NanoVDB (ReadAccessor + SampleFromVoxels, one accessor per
// thread as NanoVDB prescribes). Two fields: a smooth cloud (most voxels
// non-zero) and sparse blobs (~3 % non-zero); two access patterns: points
// along rays in 0.5-voxel steps (what tracking does) and uniformly random points.
// Also: the cost of building a majorant grid over them, per cell size.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include <nanovdb/util/OpenToNanoVDB.h>
#include <nanovdb/util/SampleFromVoxels.h>
#include <openvdb/openvdb.h>

#include "core/rng.h"
#include "core/sampling.h"
#include "grids/majorant_grid.h"
#include "grids/voxel_grid.h"

using namespace chlorovdb;

namespace {

constexpr int N = 256;

// The shared benchmark cloud (/work/shared/bench/cloud/gen_cloud.py), evaluated at N^3.
float cloud(int i, int j, int k) {
  const float h = 2.f / N;
  const float x = -1.f + (i + 0.5f) * h, y = -1.f + (j + 0.5f) * h, z = -1.f + (k + 0.5f) * h;
  const float blobs[5][5] = {{0.f, 0.f, 0.f, 0.30f, 1.f},     {0.30f, 0.15f, 0.10f, 0.20f, 0.7f},
                             {-0.28f, 0.1f, -0.15f, 0.22f, 0.8f}, {0.10f, -0.25f, 0.25f, 0.18f, 0.6f},
                             {-0.10f, 0.30f, -0.05f, 0.16f, 0.5f}};
  float d = 0;
  for (const auto& b : blobs)
    d += b[4] * std::exp(-((x - b[0]) * (x - b[0]) + (y - b[1]) * (y - b[1]) + (z - b[2]) * (z - b[2])) / (2 * b[3] * b[3]));
  auto w = [](float t) { return (1 - t * t) * (1 - t * t); };
  const float v = d * w(x) * w(y) * w(z);
  return v > 1e-3f ? v : 0.f;  // a fog volume's background is exactly zero
}

// Random balls of radius 4-12 voxels until ~3 % of the voxels are non-zero.
std::vector<float> sparse_blobs() {
  std::vector<float> v(size_t(N) * N * N, 0.f);
  Rng rng(1, 0);
  size_t filled = 0;
  while (filled < v.size() * 3 / 100) {
    const float cx = rng.uniform() * N, cy = rng.uniform() * N, cz = rng.uniform() * N, r = 4 + 8 * rng.uniform();
    for (int k = std::max(0, int(cz - r)); k < std::min(N, int(cz + r) + 1); ++k)
      for (int j = std::max(0, int(cy - r)); j < std::min(N, int(cy + r) + 1); ++j)
        for (int i = std::max(0, int(cx - r)); i < std::min(N, int(cx + r) + 1); ++i) {
          const float d2 = (i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz);
          float& x = v[i + size_t(N) * (j + size_t(N) * k)];
          if (d2 < r * r && x == 0.f) x = 1.f - std::sqrt(d2) / r + 0.01f, ++filled;
        }
  }
  return v;
}

struct Field {
  DenseGrid dense;
  VoxelGrid bricked;
  nanovdb::GridHandle<nanovdb::HostBuffer> nano;
  std::vector<Vec3> along_rays, random;
};

const Field& field(int which) {
  static std::map<int, std::unique_ptr<Field>> cache;
  auto& f = cache[which];
  if (f) return *f;
  f = std::make_unique<Field>();
  f->dense = DenseGrid({N, N, N});
  if (which == 0) {
    for (int k = 0; k < N; ++k)
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) f->dense.at(i, j, k) = cloud(i, j, k);
  } else {
    f->dense.values = sparse_blobs();
  }
  f->bricked = VoxelGrid::from_dense(f->dense);
  openvdb::initialize();
  auto vdb = openvdb::FloatGrid::create(0.f);
  auto acc = vdb->getAccessor();
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i)
        if (const float v = f->dense.at(i, j, k); v != 0.f) acc.setValue({i, j, k}, v);
  f->nano = nanovdb::openToNanoVDB(*vdb);

  Rng rng(2, 0);
  for (int i = 0; i < (1 << 20); ++i) f->random.push_back(Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * float(N - 1));
  while (f->along_rays.size() < (1u << 20)) {
    const Vec3 o = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * float(N - 1);
    const Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()}) * 0.5f;
    for (Vec3 p = o; p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < N - 1 && p.y < N - 1 && p.z < N - 1; p += d)
      f->along_rays.push_back(p);
  }
  return *f;
}

const std::vector<Vec3>& points(const Field& f, int pattern) { return pattern == 0 ? f.along_rays : f.random; }

float dense_trilinear(const DenseGrid& g, const Vec3& p) {
  const int x = int(p.x), y = int(p.y), z = int(p.z);  // p is inside [0, N-1): no clamping needed
  const float wx = p.x - x, wy = p.y - y, wz = p.z - z;
  const size_t sy = size_t(N), sz = size_t(N) * N;
  const float* v = g.values.data() + x + sy * y + sz * z;
  const float c00 = v[0] + wx * (v[1] - v[0]), c10 = v[sy] + wx * (v[sy + 1] - v[sy]);
  const float c01 = v[sz] + wx * (v[sz + 1] - v[sz]), c11 = v[sz + sy] + wx * (v[sz + sy + 1] - v[sz + sy]);
  const float c0 = c00 + wy * (c10 - c00), c1 = c01 + wy * (c11 - c01);
  return c0 + wz * (c1 - c0);
}

template <typename Lookup>
void run(benchmark::State& state, const std::vector<Vec3>& pts, Lookup lookup, size_t bytes) {
  size_t i = 0;
  float sum = 0;
  for (auto _ : state) {
    for (int k = 0; k < 4096; ++k) {
      sum += lookup(pts[i]);
      if (++i == pts.size()) i = 0;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(int64_t(state.iterations()) * 4096);
  state.counters["MB"] = double(bytes) / 1e6;
}

void BM_DenseArray_Trilinear(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  run(state, points(f, int(state.range(1))), [&](const Vec3& p) { return dense_trilinear(f.dense, p); },
      f.dense.values.size() * sizeof(float));
}

void BM_VoxelGrid_Trilinear(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  run(state, points(f, int(state.range(1))), [&](const Vec3& p) { return f.bricked.trilinear(p); },
      f.bricked.memory_bytes());
}

void BM_VoxelGrid_Nearest(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  run(state, points(f, int(state.range(1))), [&](const Vec3& p) { return f.bricked.nearest(p); },
      f.bricked.memory_bytes());
}

void BM_NanoVDB_Trilinear(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  const auto* grid = f.nano.grid<float>();
  auto acc = grid->getAccessor();
  auto sampler = nanovdb::createSampler<1>(acc);
  run(state, points(f, int(state.range(1))), [&](const Vec3& p) { return sampler(nanovdb::Vec3f(p.x, p.y, p.z)); },
      f.nano.size());
}

void BM_NanoVDB_Nearest(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  const auto* grid = f.nano.grid<float>();
  auto acc = grid->getAccessor();
  auto sampler = nanovdb::createSampler<0>(acc);
  run(state, points(f, int(state.range(1))), [&](const Vec3& p) { return sampler(nanovdb::Vec3f(p.x, p.y, p.z)); },
      f.nano.size());
}

// Building the majorant grid over a 256^3 field at one cell size: a medium that
// chooses its cell size (media/medium.cpp) builds one per candidate, 4 to 16 voxels.
void BM_MajorantGrid_Build(benchmark::State& state) {
  const Field& f = field(int(state.range(0)));
  const VoxelGrid* grids[] = {&f.bricked};
  for (auto _ : state) {
    MajorantGrid m(grids, int(state.range(1)), Interpolation::trilinear);
    benchmark::DoNotOptimize(m.resolution());
  }
}

// Args: field (0 cloud, 1 sparse blobs), pattern (0 along rays, 1 random).
void args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"field", "random"});
  for (int field : {0, 1})
    for (int pattern : {0, 1}) b->Args({field, pattern});
}

}  // namespace

BENCHMARK(BM_DenseArray_Trilinear)->Apply(args);
BENCHMARK(BM_VoxelGrid_Trilinear)->Apply(args);
BENCHMARK(BM_NanoVDB_Trilinear)->Apply(args);
BENCHMARK(BM_VoxelGrid_Nearest)->Apply(args);
BENCHMARK(BM_MajorantGrid_Build)
    ->ArgNames({"field", "voxels_per_cell"})
    ->ArgsProduct({{0, 1}, {4, 6, 8, 12, 16}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NanoVDB_Nearest)->Apply(args);
