#pragma once
// VoxelGrid: the renderer's read-only copy of one float grid, sampled in the
// index space of the OpenVDB grid it came from (voxel (i,j,k) has its value at
// the index-space point (i,j,k), as OpenVDB's BoxSampler assumes).
//
// Storage: 8^3 bricks aligned as OpenVDB leaf nodes, each stored as 9^3 floats
// (the brick plus a one-voxel apron on its +x/+y/+z sides), so the whole 2x2x2
// trilinear stencil of any lookup sits in one brick: one table load and eight
// loads at fixed offsets, no branch on brick borders. Bricks holding only the
// background value all point at one shared brick, so sparse grids stay small.
// docs/performance-grids.md has the measurement that chose this over NanoVDB.
//
// This header does not include OpenVDB (see grids/vdb_file.h for files).
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"

namespace chlorovdb {

// Lookups run in float index space, exact to one voxel only within ±2^24: grids with indices
// beyond it are refused (VoxelGrid::from_bricks), and voxelize refuses to make them.
inline constexpr int kMaxVoxelIndex = 1 << 24;

enum class Interpolation { trilinear, nearest };

// How far past the centres of the outermost stored voxels a lookup can still
// differ from the background, in voxels: a nearest lookup reads a voxel over
// its cell (half a voxel each side), a trilinear one fades it out over one voxel.
inline float support_radius(Interpolation interpolation) {
  return interpolation == Interpolation::trilinear ? 1.f : 0.5f;
}

using Coord = std::array<int, 3>;

// Where a grid came from and what its values mean (the .vdb metadata "unit",
// "scale", "length_unit" and "provenance" that write_concentration_grid stores).
struct GridMetadata {
  std::string name;        // grid name in the file
  std::string file;        // source path; empty for grids built in memory
  std::string unit;        // unit of value * scale, e.g. "uM"; empty when the file does not say
  float scale = 1.f;       // stored value * scale = quantity in `unit`
  std::string length_unit; // unit of the index-to-world transform ("m", "cm", ...); empty = metres
  std::string provenance;  // free text: who made the grid and how
  std::string converted_from;  // value type of the file's grid when it was not float ("double"), else empty
  int64_t clamped_voxels = 0;  // NaN / Inf / negative values clamped to 0 (clamp_invalid)
};

// Values on a box of voxels: builds grids in memory (tests, tools) and is what
// write_concentration_grid writes.
struct DenseGrid {
  Coord dims{0, 0, 0};            // voxels per axis
  Coord origin{0, 0, 0};          // index of the first voxel
  std::vector<float> values;      // values[x + dims[0] * (y + dims[1] * z)], x fastest, relative to origin
  Transform world_from_index;     // voxel centre (i,j,k) -> world (metadata.length_unit, metres by default)
  float background = 0.f;         // value everywhere outside the box
  GridMetadata metadata;          // name, unit, scale, provenance

  DenseGrid() = default;
  DenseGrid(Coord dims, float fill = 0.f) : dims(dims), values(size_t(dims[0]) * dims[1] * dims[2], fill) {}
  float& at(int x, int y, int z) { return values[x + size_t(dims[0]) * (y + size_t(dims[1]) * z)]; }
  float at(int x, int y, int z) const { return values[x + size_t(dims[0]) * (y + size_t(dims[1]) * z)]; }
};

// Counts of values a concentration grid must not hold.
struct InvalidValueCounts {
  int64_t nan = 0, inf = 0, negative = 0;
  int64_t total() const { return nan + inf + negative; }
};

class VoxelGrid {
 public:
  static constexpr int kBrickSize = 8;                  // voxels per brick edge (OpenVDB leaf size)
  static constexpr int kBrickStride = kBrickSize + 1;   // stored edge: brick + apron
  static constexpr int kBrickValues = kBrickStride * kBrickStride * kBrickStride;

  // Fills the kBrickValues values of voxels brick_origin + [0, 8]^3 (x fastest).
  // Called concurrently for different bricks.
  using BrickFill = std::function<void(Coord brick_origin, float* values)>;
  // Conservative and cheap: false only if every voxel of brick_origin + [0, 8]^3 is background.
  using BrickMayHoldData = std::function<bool(Coord brick_origin)>;

  VoxelGrid() = default;

  // Values outside [index_lo, index_hi] (inclusive) are `background`. Invalid
  // values (NaN, Inf, negative) throw InputError naming metadata.file / name
  // with their counts, unless clamp_invalid: then they become 0 and the count
  // is kept in metadata().clamped_voxels.
  static VoxelGrid from_bricks(Coord index_lo, Coord index_hi, float background, const Transform& world_from_index,
                               GridMetadata metadata, const BrickMayHoldData& may_hold_data, const BrickFill& fill,
                               bool clamp_invalid = false);
  static VoxelGrid from_dense(const DenseGrid& dense, bool clamp_invalid = false);

  // Index-space lookups (p in voxel units, voxel centres on integers).
  float lookup(const Vec3& p_index, Interpolation interpolation) const {
    return interpolation == Interpolation::trilinear ? trilinear(p_index) : nearest(p_index);
  }
  inline float trilinear(const Vec3& p_index) const;
  inline float nearest(const Vec3& p_index) const;
  // The stored value of one voxel (background outside the stored region).
  float voxel(int x, int y, int z) const;
  // Min and max of the voxel values in the inclusive index box [lo, hi].
  std::pair<float, float> min_max(Coord lo, Coord hi) const;
  // The values of [lo, hi] into out (x fastest, (hi - lo + 1) per axis; background
  // outside the stored voxels): a brick's row at a time, not a lookup per voxel.
  void copy_block(Coord lo, Coord hi, float* out) const;
  // Their mean (the background counts for voxels outside the stored ones).
  float mean(Coord lo, Coord hi) const;

  const Transform& world_from_index() const { return world_from_index_; }
  // Places the same voxels elsewhere in the world (a scene's length unit).
  void set_world_from_index(const Transform& world_from_index) {
    world_from_index_ = world_from_index;
    index_from_world_ = world_from_index.inverse();
  }
  const Transform& index_from_world() const { return index_from_world_; }
  // Voxels that may differ from the background (inclusive).
  Coord index_lo() const { return index_lo_; }
  Coord index_hi() const { return index_hi_; }
  // Continuous index-space box outside which every lookup of this interpolation
  // returns the background: [lo - r, hi + r] with r = support_radius(interpolation).
  Bounds3 index_bounds(Interpolation interpolation) const;
  // Axis-aligned world box around index_bounds(interpolation).
  Bounds3 world_bounds(Interpolation interpolation) const;
  float background() const { return background_; }
  float min_value() const { return min_value_; }  // over stored voxels and background
  float max_value() const { return max_value_; }
  size_t memory_bytes() const { return pool_.size() * sizeof(float) + table_.size() * sizeof(uint32_t); }
  size_t allocated_bricks() const { return pool_.size() / kBrickValues - 1; }  // without the shared background brick
  const GridMetadata& metadata() const { return metadata_; }

 private:
  // f(value, count) for the voxels of [lo, hi]: stored ones one by one, each whole
  // background brick and the part of the box outside the stored voxels in one call.
  template <typename F>
  void for_each_value(Coord lo, Coord hi, F&& f) const;
  // The stored value of voxel brick_base_ + i; i must lie in [0, 8 * bricks_).
  const float* brick_values(int ix, int iy, int iz) const {
    const int b = (ix >> 3) + bricks_[0] * ((iy >> 3) + bricks_[1] * (iz >> 3));
    return pool_.data() + size_t(table_[b]) * kBrickValues + (ix & 7) + kBrickStride * ((iy & 7) + kBrickStride * (iz & 7));
  }

  Coord index_lo_{0, 0, 0}, index_hi_{-1, -1, -1};
  Coord brick_base_{0, 0, 0};  // index of voxel 0 of brick 0 (a multiple of 8 on each axis)
  Coord bricks_{0, 0, 0};      // bricks per axis
  Vec3 brick_base_f_;          // brick_base_ as floats
  Vec3 extent_f_;              // 8 * bricks_: lookups need 0 <= p - brick_base_ < extent_f_
  float background_ = 0.f, min_value_ = 0.f, max_value_ = 0.f;
  std::vector<uint32_t> table_;  // per brick: its slot in pool_ (0 = the shared background brick)
  std::vector<float> pool_;      // kBrickValues floats per slot
  Transform world_from_index_, index_from_world_;
  GridMetadata metadata_;
};

// Trilinear interpolation between the eight voxel centres around p, exactly as
// OpenVDB's BoxSampler (so linear fields are reproduced exactly).
inline float VoxelGrid::trilinear(const Vec3& p_index) const {
  const float qx = p_index.x - brick_base_f_.x, qy = p_index.y - brick_base_f_.y, qz = p_index.z - brick_base_f_.z;
  // Written so NaN fails too; the float test comes first because casting an
  // out-of-range float to int is undefined. Outside, all eight corners are background.
  if (!(qx >= 0.f && qy >= 0.f && qz >= 0.f && qx < extent_f_.x && qy < extent_f_.y && qz < extent_f_.z))
    return background_;
  // q >= 0 here, so truncation is floor (and much cheaper than std::floor without SSE4.1).
  const int ix = int(qx), iy = int(qy), iz = int(qz);
  const float wx = qx - float(ix), wy = qy - float(iy), wz = qz - float(iz);
  const float* v = brick_values(ix, iy, iz);
  constexpr int Y = kBrickStride, Z = kBrickStride * kBrickStride;
  const float c00 = v[0] + wx * (v[1] - v[0]);
  const float c10 = v[Y] + wx * (v[Y + 1] - v[Y]);
  const float c01 = v[Z] + wx * (v[Z + 1] - v[Z]);
  const float c11 = v[Z + Y] + wx * (v[Z + Y + 1] - v[Z + Y]);
  const float c0 = c00 + wy * (c10 - c00);
  const float c1 = c01 + wy * (c11 - c01);
  return c0 + wz * (c1 - c0);
}

inline float VoxelGrid::nearest(const Vec3& p_index) const {
  const float qx = p_index.x - brick_base_f_.x + 0.5f, qy = p_index.y - brick_base_f_.y + 0.5f,
              qz = p_index.z - brick_base_f_.z + 0.5f;
  if (!(qx >= 0.f && qy >= 0.f && qz >= 0.f && qx < extent_f_.x && qy < extent_f_.y && qz < extent_f_.z))
    return background_;
  return *brick_values(int(qx), int(qy), int(qz));
}

}  // namespace chlorovdb
