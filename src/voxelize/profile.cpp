#include "voxelize/profile.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "core/keyword.h"
#include "core/rng.h"
#include "grids/vdb_file.h"
#include "grids/voxel_grid.h"

namespace chlorovdb {
namespace {

// f(d/L) reaches its limit to within 1e-4 at d = L ln(1e4).
constexpr float kFalloffRange = 9.2103404f;

float lattice_value(int x, int y, int z, uint64_t seed) {
  uint64_t h = hash_combine(seed, uint64_t(uint32_t(x)));
  h = hash_combine(h, uint64_t(uint32_t(y)));
  h = hash_combine(h, uint64_t(uint32_t(z)));
  return float(double(h >> 11) * 0x1.0p-53 * 2.0 - 1.0);  // 53 uniform bits -> [-1, 1)
}

float quintic(float t) { return t * t * t * (t * (t * 6.f - 15.f) + 10.f); }

void check(bool ok, std::string_view source, std::string_view key, float value, std::string_view problem) {
  if (!ok) throw InputError(source, key, fmt::format("{}", value), problem);
}

}  // namespace

bool parse_profile_kind(std::string_view word, ProfileKind* kind) {
  return parse_keyword(
      word, {ProfileKind::uniform, ProfileKind::linear, ProfileKind::noise, ProfileKind::falloff, ProfileKind::grid},
      kind);
}

std::string_view to_string(ProfileKind kind) {
  switch (kind) {
    case ProfileKind::uniform: return "uniform";
    case ProfileKind::linear: return "linear";
    case ProfileKind::noise: return "noise";
    case ProfileKind::falloff: return "falloff";
    case ProfileKind::grid: return "grid";
  }
  return "?";
}

std::string_view to_string(FalloffShape shape) { return shape == FalloffShape::decay ? "decay" : "rise"; }

bool parse_falloff_shape(std::string_view word, FalloffShape* shape) {
  return parse_keyword(word, {FalloffShape::decay, FalloffShape::rise}, shape);
}

double molar_per_unit(std::string_view unit) {
  if (unit == "M" || unit == "mol/L") return 1.0;
  if (unit == "mM") return 1e-3;
  if (unit == "uM" || unit == "µM") return 1e-6;
  if (unit == "nM") return 1e-9;
  return 0.0;
}

float value_noise(const Vec3& p, uint64_t seed) {
  const float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const int x = int(fx), y = int(fy), z = int(fz);
  const float u = quintic(p.x - fx), v = quintic(p.y - fy), w = quintic(p.z - fz);
  float c[2][2];
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j) {
      const float a = lattice_value(x, y + j, z + k, seed), b = lattice_value(x + 1, y + j, z + k, seed);
      c[k][j] = a + u * (b - a);
    }
  const float c0 = c[0][0] + v * (c[0][1] - c[0][0]), c1 = c[1][0] + v * (c[1][1] - c[1][0]);
  return c0 + w * (c1 - c0);
}

float fractal_noise(const Vec3& p, uint64_t seed, int octaves) {
  float sum = 0.f, norm = 0.f, amplitude = 1.f, frequency = 1.f;
  for (int o = 0; o < octaves; ++o) {
    // Each octave its own lattice (seed) so octaves do not line up at the origin.
    sum += amplitude * value_noise(p * frequency, hash_combine(seed, uint64_t(o)));
    norm += amplitude;
    amplitude *= 0.5f;
    frequency *= 2.f;
  }
  return sum / norm;
}

ProfileSampler::ProfileSampler(const ConcentrationProfile& profile, const Bounds3& body, std::string_view unit,
                               std::string_view source)
    : profile_(profile), body_(body) {
  const ConcentrationProfile& p = profile_;
  const char* kNonNegative = "must be a finite concentration >= 0";
  switch (p.kind) {
    case ProfileKind::uniform:
      check(std::isfinite(p.concentration) && p.concentration >= 0.f, source, "--concentration", p.concentration,
            kNonNegative);
      break;
    case ProfileKind::linear:
      check(std::isfinite(p.c0) && p.c0 >= 0.f, source, "--gradient (C0)", p.c0, kNonNegative);
      check(std::isfinite(p.c1) && p.c1 >= 0.f, source, "--gradient (C1)", p.c1, kNonNegative);
      check(p.axis >= 0 && p.axis <= 2, source, "--axis", float(p.axis), "must be x, y or z");
      break;
    case ProfileKind::noise:
      check(std::isfinite(p.concentration) && p.concentration >= 0.f, source, "--concentration", p.concentration,
            kNonNegative);
      check(p.noise_amplitude >= 0.f && p.noise_amplitude <= 1.f, source, "--noise-amplitude", p.noise_amplitude,
            "must lie in [0, 1] (the relative modulation around C)");
      check(std::isfinite(p.noise_scale) && p.noise_scale >= 0.f, source, "--noise-scale", p.noise_scale,
            "must be a feature size in metres > 0 (or 0 for a quarter of the body's size)");
      check(p.noise_octaves >= 1 && p.noise_octaves <= 8, source, "--noise-octaves", float(p.noise_octaves),
            "must lie in 1..8");
      noise_scale_ = p.noise_scale > 0.f ? p.noise_scale : 0.25f * max_component(body.diagonal());
      if (!(noise_scale_ > 0.f)) noise_scale_ = 1.f;
      break;
    case ProfileKind::falloff:
      check(std::isfinite(p.concentration) && p.concentration >= 0.f, source, "--concentration", p.concentration,
            kNonNegative);
      check(std::isfinite(p.falloff_length) && p.falloff_length > 0.f, source, "--falloff-length", p.falloff_length,
            "must be a length in metres > 0");
      break;
    case ProfileKind::grid: {
      if (p.grid_file.empty()) throw InputError(source, "--source-grid", "", "the grid profile needs a .vdb file");
      grid_ = std::make_unique<VoxelGrid>(load_concentration_grid(p.grid_file, p.grid_name));
      const GridMetadata& m = grid_->metadata();
      const double to = molar_per_unit(unit);
      double from = to;  // a grid that names no unit is taken to be in ours
      if (!m.unit.empty()) {
        from = molar_per_unit(m.unit);
        if (from == 0.0)
          throw InputError(p.grid_file.string(), "unit", m.unit,
                           "unknown concentration unit; use M, mM, uM (µM) or nM");
      }
      grid_factor_ = float(double(m.scale) * from / to);
      break;
    }
  }
}

ProfileSampler::~ProfileSampler() = default;
ProfileSampler::ProfileSampler(ProfileSampler&&) noexcept = default;

float ProfileSampler::value(const Vec3& p_world, float depth) const {
  const ConcentrationProfile& p = profile_;
  switch (p.kind) {
    case ProfileKind::uniform: return p.concentration;
    case ProfileKind::linear: {
      const float lo = body_.lo[p.axis], hi = body_.hi[p.axis];
      const float t = hi > lo ? std::clamp((p_world[p.axis] - lo) / (hi - lo), 0.f, 1.f) : 0.5f;
      return p.c0 + t * (p.c1 - p.c0);
    }
    case ProfileKind::noise:
      return p.concentration *
             std::max(0.f, 1.f + p.noise_amplitude * fractal_noise(p_world / noise_scale_, p.seed, p.noise_octaves));
    case ProfileKind::falloff: {
      const float e = std::exp(-std::max(depth, 0.f) / p.falloff_length);
      return p.concentration * (p.falloff_shape == FalloffShape::decay ? e : 1.f - e);
    }
    case ProfileKind::grid:
      return std::max(0.f, grid_factor_ * grid_->trilinear(grid_->index_from_world().point(p_world)));
  }
  return 0.f;
}

bool ProfileSampler::varies_with_position() const {
  return profile_.kind == ProfileKind::linear || profile_.kind == ProfileKind::noise ||
         profile_.kind == ProfileKind::grid;
}

float ProfileSampler::depth_range() const {
  return profile_.kind == ProfileKind::falloff ? kFalloffRange * profile_.falloff_length : 0.f;
}

std::string ProfileSampler::describe() const {
  const ConcentrationProfile& p = profile_;
  switch (p.kind) {
    case ProfileKind::uniform: return fmt::format("--profile uniform --concentration {}", p.concentration);
    case ProfileKind::linear:
      return fmt::format("--profile linear --gradient {},{} --axis {}", p.c0, p.c1, "xyz"[p.axis]);
    case ProfileKind::noise:
      return fmt::format("--profile noise --concentration {} --noise-seed {} --noise-scale {} --noise-amplitude {} "
                         "--noise-octaves {}",
                         p.concentration, p.seed, noise_scale_, p.noise_amplitude, p.noise_octaves);
    case ProfileKind::falloff:
      return fmt::format("--profile falloff --concentration {} --falloff-length {} --falloff-shape {}",
                         p.concentration, p.falloff_length, to_string(p.falloff_shape));
    case ProfileKind::grid:
      return fmt::format("--profile grid --source-grid {} --source-grid-name {}", p.grid_file.string(), p.grid_name);
  }
  return {};
}

}  // namespace chlorovdb
