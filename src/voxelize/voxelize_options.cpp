// Checking options, estimating cost and describing a conversion: the parts of
// voxelize/ that need no OpenVDB (they compile in a second, voxelize.cpp does not).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/keyword.h"
#include "voxelize/voxelize.h"

namespace chlorovdb {
namespace {

// meshToVolume does not expand a band narrower than two voxels.
constexpr float kMinBandVoxels = 2.f;

std::string source_of(const VoxelizeOptions& o) { return o.source_name.empty() ? std::string("<mesh>") : o.source_name; }

std::string format_size(const Vec3& h) {
  return h.x == h.y && h.y == h.z ? fmt::format("{}", h.x) : fmt::format("{},{},{}", h.x, h.y, h.z);
}

std::string format_bytes(double bytes) {
  const char* units[] = {"B", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) bytes /= 1024.0, ++u;
  return fmt::format("{:.3g} {}", bytes, units[u]);
}

}  // namespace

std::string_view to_string(VoxelizeMode mode) {
  switch (mode) {
    case VoxelizeMode::solid: return "solid";
    case VoxelizeMode::shell: return "shell";
    case VoxelizeMode::spill: return "spill";
  }
  return "?";
}

bool parse_voxelize_mode(std::string_view word, VoxelizeMode* mode) {
  return parse_keyword(word, {VoxelizeMode::solid, VoxelizeMode::shell, VoxelizeMode::spill}, mode);
}

std::string_view to_string(SpillDirection direction) { return direction == SpillDirection::normal ? "normal" : "up"; }

bool parse_spill_direction(std::string_view word, SpillDirection* direction) {
  return parse_keyword(word, {SpillDirection::normal, SpillDirection::up}, direction);
}

void validate_options(const VoxelizeOptions& o) {
  const std::string source = source_of(o);
  const Vec3 h = o.voxel_size;
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(h[a]) && h[a] > 0.f))
      throw InputError(source, "--voxel-size", format_size(h),
                       "must be positive and finite (metres per voxel: one value, or vx,vy,vz)");
  if (o.mode == VoxelizeMode::shell && !(std::isfinite(o.thickness) && o.thickness > 0.f))
    throw InputError(source, "--thickness", fmt::format("{}", o.thickness),
                     "a shell needs a thickness in metres > 0");
  if (o.mode == VoxelizeMode::spill && !(std::isfinite(o.depth) && o.depth > 0.f))
    throw InputError(source, "--depth", fmt::format("{}", o.depth), "a spill needs a depth in metres > 0");
  if (!(std::isfinite(o.height_field_cell) && o.height_field_cell >= 0.f))
    throw InputError(source, "--cell-size", fmt::format("{}", o.height_field_cell),
                     "must be a length in metres > 0 (or 0 for the voxel size)");
  if (molar_per_unit(o.unit) == 0.0)
    throw InputError(source, "--unit", o.unit, "unknown concentration unit; use M, mM, uM (µM) or nM");
  if (o.grid_name.empty()) throw InputError(source, "--grid-name", "", "the output grid needs a name");
  if (o.memory_limit_bytes < 0)
    throw InputError(source, "memory_limit_bytes", fmt::format("{}", o.memory_limit_bytes), "must be >= 0");
}

std::string describe_options(const VoxelizeOptions& o, const ProfileSampler& profile) {
  std::string s = fmt::format("chlorovdb voxelize {} --mode {} --voxel-size {}", source_of(o), to_string(o.mode),
                              format_size(o.voxel_size));
  if (o.mode == VoxelizeMode::shell) s += fmt::format(" --thickness {}", o.thickness);
  if (o.mode == VoxelizeMode::spill)
    s += fmt::format(" --depth {} --direction {}", o.depth,
                     to_string(o.spill_direction));
  if (o.height_field_cell > 0.f) s += fmt::format(" --cell-size {}", o.height_field_cell);
  s += fmt::format(" {} --unit {} --grid-name {}", profile.describe(), o.unit, o.grid_name);
  if (!o.world_from_input.is_identity()) {
    const auto& m = o.world_from_input.matrix();
    s += fmt::format(" (input transform, rows: {} {} {} {} / {} {} {} {} / {} {} {} {})", m[0][0], m[0][1], m[0][2],
                     m[0][3], m[1][0], m[1][1], m[1][2], m[1][3], m[2][0], m[2][1], m[2][2], m[2][3]);
  }
  return s;
}

namespace detail {

BandWidths band_widths(const VoxelizeOptions& o, float depth_needed) {
  const Vec3 h = o.voxel_size;
  const float h_min = std::min({h.x, h.y, h.z});
  // Index distance <= world distance / h_min, so d / h_min index voxels hold every voxel within d metres.
  // A voxel can be partly covered while its centre lies within its half-diagonal of the surface;
  // one more voxel of slack so the band never cuts such a voxel.
  const float ramp = 0.5f * length(h) / h_min + 1.f;
  if (o.mode == VoxelizeMode::shell) {
    const float w = std::max(kMinBandVoxels, 0.5f * o.thickness / h_min + ramp);
    return {w, w};  // unsigned: the band lies on both sides of the surface
  }
  return {std::max(kMinBandVoxels, ramp), std::max(kMinBandVoxels, depth_needed / h_min + ramp)};
}

double index_space_area(const TriangleMesh& mesh, const Vec3& h) {
  double sum = 0;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
               c = mesh.positions[mesh.indices[3 * t + 2]];
    const Vec3 ab{(b.x - a.x) / h.x, (b.y - a.y) / h.y, (b.z - a.z) / h.z};
    const Vec3 ac{(c.x - a.x) / h.x, (c.y - a.y) / h.y, (c.z - a.z) / h.z};
    sum += 0.5 * double(length(cross(ab, ac)));
  }
  return sum;
}

double enclosed_volume(const TriangleMesh& mesh) {
  // Divergence theorem: Σ signed tetrahedron volumes against the first vertex (kept near the mesh for precision).
  if (mesh.positions.empty()) return 0;
  const Vec3 o = mesh.positions[0];
  double sum = 0;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 a = mesh.positions[mesh.indices[3 * t]] - o, b = mesh.positions[mesh.indices[3 * t + 1]] - o,
               c = mesh.positions[mesh.indices[3 * t + 2]] - o;
    sum += double(a.x) * (double(b.y) * c.z - double(b.z) * c.y) - double(a.y) * (double(b.x) * c.z - double(b.z) * c.x) +
           double(a.z) * (double(b.x) * c.y - double(b.y) * c.x);
  }
  return sum / 6.0;
}

Bounds3 mesh_bounds(const TriangleMesh& mesh) {
  Bounds3 b;
  for (const Vec3& p : mesh.positions) b.extend(p);
  return b;
}

}  // namespace detail

VoxelEstimate estimate_voxels(const TriangleMesh& mesh, const VoxelizeOptions& o, const ProfileSampler& profile) {
  const Vec3 h = o.voxel_size;
  const double voxel_volume = double(h.x) * h.y * h.z;
  const detail::BandWidths band = detail::band_widths(o, profile.depth_range());
  const double area = detail::index_space_area(mesh, h);  // voxel faces
  VoxelEstimate e;
  e.band_voxels = area * (band.exterior + band.interior);
  // The surface layer of partly covered voxels is about one voxel thick (area in voxel faces).
  e.body_voxels = o.mode == VoxelizeMode::shell ? double(mesh_area(mesh)) * o.thickness / voxel_volume + area
                                                : std::abs(detail::enclosed_volume(mesh)) / voxel_volume + area;
  // Leaves are 8^3 voxels: a band is stored with up to 7 voxels of padding on each side.
  const double band_leaf_voxels = area * (band.exterior + band.interior + 8.0);
  const bool dense = o.mode == VoxelizeMode::shell || profile.varies_with_position();
  e.stored_voxels = dense ? e.body_voxels : std::min(e.body_voxels, band_leaf_voxels);
  // meshToVolume: distance (float) + closest triangle (int32) per band voxel, and about as much again
  // in its per-thread voxelization data; the fog: one float per stored voxel; 25 % tree overhead.
  e.bytes = 1.25 * (band_leaf_voxels * 16.0 + std::max(e.stored_voxels, band_leaf_voxels) * 4.0);
  e.available_bytes = o.memory_limit_bytes > 0 ? o.memory_limit_bytes : available_memory_bytes();
  return e;
}

void check_index_range(const Bounds3& body, double margin_voxels, const VoxelizeOptions& o) {
  const Vec3 h = o.voxel_size;
  const std::array<double, 3> lo{body.lo.x / double(h.x), body.lo.y / double(h.y), body.lo.z / double(h.z)},
      hi{body.hi.x / double(h.x), body.hi.y / double(h.y), body.hi.z / double(h.z)};
  for (int a = 0; a < 3; ++a) {
    const double reach = std::max(std::abs(lo[size_t(a)]), std::abs(hi[size_t(a)])) + margin_voxels;
    if (!(reach <= kMaxVoxelIndex))
      throw InputError(source_of(o), "--voxel-size", format_size(o.voxel_size),
                       fmt::format("the object reaches {:.3g} voxels from the origin along {}: grids beyond ±2^24 "
                                   "voxels are refused (float lookups there are off by whole voxels). Move it near "
                                   "the origin (--translate) or use larger voxels",
                                   reach, "xyz"[a]));
  }
}

void check_estimate(const VoxelEstimate& e, const VoxelizeOptions& o) {
  const bool too_many = e.voxels() > kMaxVoxels;
  const bool too_big = e.available_bytes > 0 && e.bytes > double(e.available_bytes);
  if (!too_many && !too_big) return;
  // Body voxels scale as 1/h^3, band voxels and memory (mostly band) as 1/h^2.
  double factor = 1.0;
  if (e.body_voxels > kMaxVoxels) factor = std::max(factor, std::cbrt(e.body_voxels / kMaxVoxels));
  if (e.band_voxels > kMaxVoxels) factor = std::max(factor, std::sqrt(e.band_voxels / kMaxVoxels));
  if (too_big) factor = std::max(factor, std::sqrt(e.bytes / double(e.available_bytes)));
  const std::string memory =
      e.available_bytes > 0
          ? fmt::format("this machine has {} available ({})", format_bytes(double(e.available_bytes)),
                        o.memory_limit_bytes > 0 ? "memory limit given" : "MemAvailable in /proc/meminfo")
          : std::string("the memory available is unknown (/proc/meminfo unreadable)");
  throw InputError(
      source_of(o), "--voxel-size", format_size(o.voxel_size),
      fmt::format("needs about {:.3g} voxels ({:.3g} in the body, {:.3g} in the distance band) and about {} of "
                  "memory, refused before allocating: {}; {}. A voxel size about {:.3g} times larger would fit",
                  e.voxels(), e.body_voxels, e.band_voxels, format_bytes(e.bytes),
                  too_many ? "more than 2^31 voxels is refused" : "more memory than is available", memory,
                  1.1 * factor));
}

}  // namespace chlorovdb
