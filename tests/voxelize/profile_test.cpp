// Concentration profiles, each checked on voxels well inside the body (coverage 1).
#include <cmath>

#include "voxelize/profile.h"
#include "voxelize_test_util.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

const Bounds3 kBox{{0.0013f, 0.0021f, -0.0007f}, {0.0413f, 0.0521f, 0.0293f}};

VoxelGrid voxelize_box(const ConcentrationProfile& profile, const std::string& name, VoxelizeReport* report = nullptr) {
  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.profile = profile;
  const auto path = temp_path(name);
  const VoxelizeReport r = voxelize_mesh(make_box(kBox), o, path);
  if (report) *report = r;
  return load_concentration_grid(path, "density");
}

}  // namespace

TEST(VoxelizeProfile, UniformFillsTheInteriorWithC) {
  ConcentrationProfile p;
  p.concentration = 5.f;
  VoxelizeReport r;
  const VoxelGrid g = voxelize_box(p, "uniform.vdb", &r);
  for (int j = 5; j <= 48; j += 7) EXPECT_EQ(g.voxel(20, j, 15), 5.f) << j;
  EXPECT_EQ(r.max_value, 5.f);
  EXPECT_NE(r.provenance.find("--profile uniform --concentration 5"), std::string::npos) << r.provenance;
}

TEST(VoxelizeProfile, LinearGoesFromC0ToC1AcrossTheBody) {
  ConcentrationProfile p;
  p.kind = ProfileKind::linear;
  p.c0 = 1.f;
  p.c1 = 5.f;
  p.axis = 1;
  const VoxelGrid g = voxelize_box(p, "linear.vdb");
  for (int j = 4; j <= 50; j += 3) {
    const float y = j * 0.001f;
    const float expected = 1.f + 4.f * (y - kBox.lo.y) / (kBox.hi.y - kBox.lo.y);
    EXPECT_NEAR(g.voxel(20, j, 15), expected, 1e-4f * expected) << j;
    EXPECT_EQ(g.voxel(20, j, 15), g.voxel(35, j, 3));  // constant across the axis
  }
}

TEST(VoxelizeProfile, NoiseIsSeededAndModulatesAroundC) {
  ConcentrationProfile p;
  p.kind = ProfileKind::noise;
  p.concentration = 2.f;
  p.noise_amplitude = 0.5f;
  p.noise_scale = 0.01f;
  p.seed = 7;
  const VoxelGrid a = voxelize_box(p, "noise_a.vdb"), b = voxelize_box(p, "noise_b.vdb");
  p.seed = 8;
  const VoxelGrid c = voxelize_box(p, "noise_c.vdb");
  double sum = 0, sum2 = 0;
  int n = 0, differ = 0;
  for (int k = 2; k <= 27; ++k)
    for (int j = 4; j <= 50; ++j)
      for (int i = 3; i <= 39; ++i) {
        const float v = a.voxel(i, j, k);
        ASSERT_EQ(v, b.voxel(i, j, k));  // same seed, same values
        differ += v != c.voxel(i, j, k) ? 1 : 0;
        ASSERT_GE(v, 1.f - 1e-5f);
        ASSERT_LE(v, 3.f + 1e-5f);
        sum += v, sum2 += double(v) * v, ++n;
      }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 2.0, 0.3);
  EXPECT_GT(sd, 0.1);
  EXPECT_GT(differ, n * 9 / 10);
}

TEST(VoxelizeProfile, ValueNoiseIsSmoothAndBounded) {
  float lo = 1.f, hi = -1.f;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p{i * 0.0137f, i * 0.0071f - 3.f, 5.f - i * 0.0113f};
    const float v = fractal_noise(p, 42, 4);
    lo = std::min(lo, v), hi = std::max(hi, v);
    // Lipschitz: a step of 1e-3 lattice units cannot move it far.
    EXPECT_LT(std::abs(fractal_noise(p + Vec3(1e-3f), 42, 4) - v), 0.05f);
  }
  EXPECT_GE(lo, -1.f);
  EXPECT_LE(hi, 1.f);
  EXPECT_LT(lo, -0.3f);
  EXPECT_GT(hi, 0.3f);
  EXPECT_EQ(value_noise({2.f, 3.f, 4.f}, 1), value_noise({2.f, 3.f, 4.f}, 1));
  EXPECT_NE(value_noise({2.f, 3.f, 4.f}, 1), value_noise({2.f, 3.f, 4.f}, 2));
}

// Falloff from the surface of a sphere: C e^(-d/L) (decay) and C (1 - e^(-d/L)) (rise), d = R - r.
TEST(VoxelizeProfile, FalloffFollowsTheDistanceFromTheSurface) {
  const float R = 0.03f, L = 0.003f, h = 0.001f;
  // The +x and -y axes pass through vertices of this tessellation, so d = R - r is exact there.
  const TriangleMesh sphere = make_uv_sphere({0.f, 0.f, 0.f}, R, 64, 128);
  for (FalloffShape shape : {FalloffShape::decay, FalloffShape::rise}) {
    VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(h));
    o.profile.kind = ProfileKind::falloff;
    o.profile.concentration = 4.f;
    o.profile.falloff_length = L;
    o.profile.falloff_shape = shape;
    const auto path = temp_path(shape == FalloffShape::decay ? "falloff_decay.vdb" : "falloff_rise.vdb");
    voxelize_mesh(sphere, o, path);
    const VoxelGrid g = load_concentration_grid(path, "density");
    for (int i = 0; i <= 28; ++i) {  // r = i h, depth from 0.002 to 0.03 (coverage 1)
      const float d = R - i * h;
      const float e = std::exp(-d / L);
      const float expected = 4.f * (shape == FalloffShape::decay ? e : 1.f - e);
      EXPECT_NEAR(g.voxel(i, 0, 0), expected, 0.01f * 4.f) << "depth " << d;
      EXPECT_NEAR(g.voxel(0, -i, 0), expected, 0.01f * 4.f) << "depth " << d;
    }
  }
}

// Sampled from another grid (in nM, scale 2) and converted to µM.
TEST(VoxelizeProfile, GridIsSampledAndConvertedToTheOutputUnit) {
  DenseGrid source({40, 40, 40});
  source.world_from_index = Transform::scale(Vec3(0.002f));
  source.metadata.name = "chl";
  source.metadata.unit = "nM";
  source.metadata.scale = 2.f;
  for (int z = 0; z < 40; ++z)
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) source.at(x, y, z) = 100.f + 1000.f * (x * 0.002f) + 500.f * (z * 0.002f);
  const auto source_path = temp_path("profile_source.vdb");
  write_concentration_grid(source_path, source);

  VoxelizeOptions o = options_with(VoxelizeMode::solid, Vec3(0.001f));
  o.profile.kind = ProfileKind::grid;
  o.profile.grid_file = source_path;
  o.profile.grid_name = "chl";
  o.unit = "uM";
  const auto path = temp_path("profile_grid.vdb");
  const VoxelizeReport r = voxelize_mesh(make_box({{0.01f, 0.01f, 0.01f}, {0.06f, 0.05f, 0.07f}}), o, path);
  const VoxelGrid g = load_concentration_grid(path, "density");
  for (int i = 12; i <= 58; i += 5)
    for (int k = 12; k <= 68; k += 7) {
      const float expected = 2.f * (100.f + 1000.f * i * 0.001f + 500.f * k * 0.001f) / 1000.f;
      EXPECT_NEAR(g.voxel(i, 30, k), expected, 1e-4f * expected) << i << ", " << k;
    }
  EXPECT_NE(r.provenance.find("--profile grid --source-grid"), std::string::npos);
  EXPECT_EQ(g.metadata().unit, "uM");
}
