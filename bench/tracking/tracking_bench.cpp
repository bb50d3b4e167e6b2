// Transmittance estimates per second against optical depth and sparsity for
// each estimator, free-flight samples per second, the majorant cell size, and
// raw grid lookups per second as the floor. Rays: 4096 random chords through
// the grid's box (the same rays for every benchmark). Media: one pigment on a
// 128^3 grid, four wavelengths whose optical depths are 1, 0.2, 0.6 and 1.2
// times the hero's, no solvent (so empty space is really empty). The "tau"
// argument is the hero's optical depth averaged over the rays.
// The sd counter is the standard deviation of one estimate of the hero lane's
// T given the chord, root-mean-square over 64 of the chords (absolute, as image
// noise is: thin chords, which carry the light, dominate it): time x sd^2
// compares the estimators' efficiency.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "tracking/sample_t_maj.h"
#include "tracking/transmittance.h"

using namespace chlorovdb;

namespace {

constexpr int N = 128;
// Majorant cells of a fixed 8 voxels, as in the figures of docs/performance-grids.md (the
// renderer now picks a size per medium; the benchmarks keep theirs comparable).
constexpr int kCellVoxels = 8;
const float kLambda[] = {650.f, 450.f, 550.f, 700.f}, kPdf[] = {1.f, 1.f, 1.f, 1.f};
const SampledWavelengths kWavelengths = SampledWavelengths::from_values(kLambda, kPdf, 4);
// eps(l) = 100 (l - 400): lanes in the ratios 25 : 5 : 15 : 30.
const Pigment kPigment{"ramp", Spectrum::tabulated({400.f, 800.f}, {0.f, 40000.f}), Spectrum::constant(0.f), 0.f};

// The shared benchmark cloud (/work/shared/bench/cloud/gen_cloud.py) at N^3.
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
  return v > 1e-3f ? v : 0.f;
}

// Balls of density 1 until `percent` of the voxels are non-zero (100: all voxels 1).
DenseGrid blobs(int percent) {
  DenseGrid g({N, N, N}, percent >= 100 ? 1.f : 0.f);
  Rng rng(uint64_t(percent), 0);
  size_t filled = percent >= 100 ? g.values.size() : 0;
  while (filled < g.values.size() * size_t(percent) / 100) {
    const float cx = rng.uniform() * N, cy = rng.uniform() * N, cz = rng.uniform() * N, r = 3 + 6 * rng.uniform();
    for (int k = std::max(0, int(cz - r)); k < std::min(N, int(cz + r) + 1); ++k)
      for (int j = std::max(0, int(cy - r)); j < std::min(N, int(cy + r) + 1); ++j)
        for (int i = std::max(0, int(cx - r)); i < std::min(N, int(cx + r) + 1); ++i)
          if ((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz) < r * r && g.at(i, j, k) == 0.f)
            g.at(i, j, k) = 1.f, ++filled;
  }
  return g;
}

std::shared_ptr<const VoxelGrid> make_grid(DenseGrid g) {
  g.world_from_index = Transform::translate({-1.f, -1.f, -1.f}) * Transform::scale(Vec3(2.f / N)) *
                       Transform::translate({0.5f, 0.5f, 0.5f});  // the cube [-1, 1]^3
  return std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(g));
}

struct Chord {
  Ray ray;
  float t_max;
};

const std::vector<Chord>& chords() {
  static const std::vector<Chord> c = [] {
    std::vector<Chord> out;
    Rng rng(7, 0);
    const Bounds3 box{{-1, -1, -1}, {1, 1, 1}};
    while (out.size() < 4096) {
      const Vec3 o = sample_uniform_sphere({rng.uniform(), rng.uniform()}) * 2.f;
      const Vec3 target = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 2.f - Vec3(1.f);
      const Ray r{o, normalize(target - o)};
      float t0, t1;
      if (intersect_bounds(box, r, 10.f, &t0, &t1)) out.push_back({{r.at(t0), r.d}, t1 - t0});
    }
    return out;
  }();
  return c;
}

// Hero optical depth of each chord per unit concentration scale, by quadrature.
std::vector<double> unit_depths(const Medium& m) {
  const PreparedMedium pm = prepare(m, kWavelengths);
  std::vector<double> tau;
  for (const Chord& c : chords()) {
    const Ray ri = m.index_ray(c.ray);
    const int steps = 1024;
    double s = 0;
    for (int i = 0; i < steps; ++i) s += m.sigma_t(ri.at((i + 0.5f) * c.t_max / steps), pm)[0];
    tau.push_back(s * c.t_max / steps);
  }
  return tau;
}

struct Scenario {
  std::unique_ptr<Medium> medium;
  PreparedMedium prepared;
};

MediumDesc grid_desc(std::shared_ptr<const VoxelGrid> grid, float scale, int voxels_per_cell) {
  MediumDesc d;
  d.pigments.push_back({kPigment, Field::from_grid(std::move(grid), scale)});
  d.majorant_voxels_per_cell = voxels_per_cell;
  return d;
}

// field: 0 cloud, else the blobs' percentage. scale_tau > 0: scale so the mean hero tau is scale_tau;
// otherwise blobs of density 1 have sigma_t = 5 /m (a chord through a full box: tau about 10).
const Scenario& scenario(int field, double mean_tau, int voxels_per_cell) {
  static std::map<std::tuple<int, double, int>, std::unique_ptr<Scenario>> cache;
  auto& s = cache[{field, mean_tau, voxels_per_cell}];
  if (s) return *s;
  static std::map<int, std::shared_ptr<const VoxelGrid>> grids;
  auto& grid = grids[field];
  if (!grid) grid = make_grid(field == 0 ? [] {
    DenseGrid g({N, N, N});
    for (int k = 0; k < N; ++k)
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) g.at(i, j, k) = cloud(i, j, k);
    return g;
  }() : blobs(field));
  const float per_molar = kAbsorptionPerMolarExtinction * kPigment.epsilon(kLambda[0]);
  float scale = 5.f / per_molar;
  if (mean_tau > 0) {
    double sum = 0;
    for (double t : unit_depths(Medium(grid_desc(grid, scale, voxels_per_cell)))) sum += t;
    scale *= float(mean_tau * double(chords().size()) / sum);
  }
  s = std::make_unique<Scenario>();
  s->medium = std::make_unique<Medium>(grid_desc(grid, scale, voxels_per_cell));
  s->prepared = prepare(*s->medium, kWavelengths);
  return *s;
}

const TransmittanceEstimator kEstimators[] = {TransmittanceEstimator::delta, TransmittanceEstimator::ratio,
                                              TransmittanceEstimator::residual_ratio,
                                              TransmittanceEstimator::closed_form};

double conditional_sd(const Medium& m, const PreparedMedium& pm, TransmittanceEstimator e) {
  Rng rng(99, 0);
  double sum_var = 0;
  const int chords_used = 64, n = 400;
  for (int c = 0; c < chords_used; ++c) {
    const Chord& chord = chords()[size_t(c) * 61 % chords().size()];
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
      const double T = transmittance(chord.ray, chord.t_max, kWavelengths, m, pm, e, rng)[0];
      s += T, s2 += T * T;
    }
    const double mean = s / n;
    sum_var += std::max(0.0, s2 / n - mean * mean) * n / (n - 1);
  }
  return std::sqrt(sum_var / chords_used);
}

void run_transmittance(benchmark::State& state, const Scenario& s, TransmittanceEstimator e) {
  const auto& c = chords();
  Rng rng(1, 0);
  size_t i = 0;
  float sum = 0;
  for (auto _ : state) {
    sum += transmittance(c[i].ray, c[i].t_max, kWavelengths, *s.medium, s.prepared, e, rng)[0];
    if (++i == c.size()) i = 0;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.counters["sd"] = conditional_sd(*s.medium, s.prepared, e);
  state.SetLabel(to_string(e));
}

// Args: estimator, mean hero tau of the cloud.
void BM_Transmittance_Cloud(benchmark::State& state) {
  run_transmittance(state, scenario(0, double(state.range(1)), kCellVoxels),
                    kEstimators[state.range(0)]);
}

// Args: estimator, percent of voxels active (density 1, sigma_t 5 /m).
void BM_Transmittance_Sparsity(benchmark::State& state) {
  run_transmittance(state, scenario(int(state.range(1)), 0.0, kCellVoxels),
                    kEstimators[state.range(0)]);
}

// Args: estimator, majorant cell edge in voxels; cloud at mean tau 10 and 10 % blobs.
void BM_MajorantCellSize_Cloud(benchmark::State& state) {
  run_transmittance(state, scenario(0, 10.0, int(state.range(1))), kEstimators[state.range(0)]);
}
void BM_MajorantCellSize_Sparse10(benchmark::State& state) {
  run_transmittance(state, scenario(10, 0.0, int(state.range(1))), kEstimators[state.range(0)]);
}

// Homogeneous medium, closed form against tracking. Args: estimator, tau over the chords' mean length.
void BM_Transmittance_Homogeneous(benchmark::State& state) {
  static std::map<int64_t, std::unique_ptr<Scenario>> cache;
  auto& s = cache[state.range(1)];
  if (!s) {
    double mean_length = 0;
    for (const Chord& c : chords()) mean_length += c.t_max;
    mean_length /= double(chords().size());
    MediumDesc d;
    d.pigments.push_back({kPigment, Field::constant(float(double(state.range(1)) / mean_length /
                                                          (kAbsorptionPerMolarExtinction * kPigment.epsilon(kLambda[0]))))});
    s = std::make_unique<Scenario>();
    s->medium = std::make_unique<Medium>(d);
    s->prepared = prepare(*s->medium, kWavelengths);
  }
  run_transmittance(state, *s, kEstimators[state.range(0)]);
}

// Free flights: sample_T_maj until the first real collision (hero lane).
// Args: mean hero tau, majorant cell edge in voxels.
void BM_FreeFlight_Cloud(benchmark::State& state) {
  const Scenario& s = scenario(0, double(state.range(0)), int(state.range(1)));
  const auto& c = chords();
  Rng rng(2, 0);
  size_t i = 0;
  int64_t collisions = 0;
  for (auto _ : state) {
    sample_T_maj(c[i].ray, c[i].t_max, rng.uniform(), rng, kWavelengths, *s.medium, s.prepared,
                 [&](const Vec3&, const MediumCollision& collision, const SampledSpectrum& sigma_maj,
                     const MajorantTransmittance&) {
                   ++collisions;
                   return rng.uniform() * sigma_maj[0] >= collision.sigma_t()[0];  // continue on null collisions
                 });
    if (++i == c.size()) i = 0;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.counters["collisions"] = double(collisions) / double(state.iterations());
}

// The floor: concentration lookups along the chords in 0.5-voxel steps, raw
// (VoxelGrid::trilinear) and as a medium's per-lane sigma_t.
void BM_GridLookup_Cloud(benchmark::State& state) {
  const Scenario& s = scenario(0, 10.0, kCellVoxels);
  const VoxelGrid& grid = *s.medium->desc().pigments[0].concentration.grid;
  std::vector<Vec3> pts;
  for (const Chord& c : chords()) {
    const Ray ri = s.medium->index_ray(c.ray);
    const float step = 0.5f / length(ri.d);
    for (float t = 0; t < c.t_max; t += step) pts.push_back(ri.at(t));
  }
  size_t i = 0;
  float sum = 0;
  const bool as_sigma_t = state.range(0) == 1;
  for (auto _ : state) {
    for (int k = 0; k < 1024; ++k) {
      sum += as_sigma_t ? s.medium->sigma_t(pts[i], s.prepared)[0] : grid.trilinear(pts[i]);
      if (++i == pts.size()) i = 0;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(int64_t(state.iterations()) * 1024);
  state.SetLabel(as_sigma_t ? "Medium::sigma_t, 4 lanes" : "VoxelGrid::trilinear");
}

}  // namespace

BENCHMARK(BM_GridLookup_Cloud)->ArgName("sigma_t")->Arg(0)->Arg(1);
BENCHMARK(BM_Transmittance_Cloud)->ArgNames({"estimator", "tau"})->ArgsProduct({{0, 1, 2}, {1, 10, 100}});
BENCHMARK(BM_Transmittance_Sparsity)->ArgNames({"estimator", "percent"})->ArgsProduct({{0, 1, 2}, {1, 10, 100}});
BENCHMARK(BM_Transmittance_Homogeneous)->ArgNames({"estimator", "tau"})->ArgsProduct({{0, 1, 2, 3}, {1, 10, 100}});
BENCHMARK(BM_FreeFlight_Cloud)->ArgNames({"tau", "voxels_per_cell"})->ArgsProduct({{1, 10, 100}, {2, 4, 8, 16, 32}});
BENCHMARK(BM_MajorantCellSize_Cloud)->ArgNames({"estimator", "voxels_per_cell"})->ArgsProduct({{1, 2}, {2, 4, 8, 16, 32}});
BENCHMARK(BM_MajorantCellSize_Sparse10)->ArgNames({"estimator", "voxels_per_cell"})->ArgsProduct({{1, 2}, {2, 4, 8, 16, 32}});
