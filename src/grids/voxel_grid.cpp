#include "grids/voxel_grid.h"

#include "core/memory.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <mutex>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/error.h"

namespace chlorovdb {
namespace {

int floor_div8(int v) { return v >= 0 ? v / 8 : -((-v + 7) / 8); }

// The first invalid value met, for the error message.
struct InvalidExample {
  std::mutex mutex;
  bool found = false;
  Coord where{};
  float value = 0.f;
};

bool is_invalid(float v) { return !(v >= 0.f) || std::isinf(v); }  // NaN fails v >= 0

void count_invalid(float v, InvalidValueCounts* counts) {
  if (std::isnan(v)) ++counts->nan;
  else if (std::isinf(v)) ++counts->inf;
  else if (v < 0.f) ++counts->negative;
}

}  // namespace

VoxelGrid VoxelGrid::from_bricks(Coord index_lo, Coord index_hi, float background, const Transform& world_from_index,
                                 GridMetadata metadata, const BrickMayHoldData& may_hold_data, const BrickFill& fill,
                                 bool clamp_invalid) {
  const std::string file = metadata.file.empty() ? std::string("<memory>") : metadata.file;
  if (is_invalid(background))
    throw InputError(file, "grid", metadata.name,
                     fmt::format("background value {} is not a finite non-negative number", background));

  VoxelGrid g;
  g.index_lo_ = index_lo;
  g.index_hi_ = index_hi;
  g.background_ = background;
  g.world_from_index_ = world_from_index;
  g.index_from_world_ = world_from_index.inverse();
  g.metadata_ = std::move(metadata);
  const bool empty = index_lo[0] > index_hi[0] || index_lo[1] > index_hi[1] || index_lo[2] > index_hi[2];
  if (!empty) {
    // The brick table covers the whole bounding box, however sparse: refuse
    // one the machine cannot hold before allocating (computed in double: the
    // count can exceed any integer type).
    double table_bytes = sizeof(uint32_t);
    for (int a = 0; a < 3; ++a) table_bytes *= (double(index_hi[a]) - double(index_lo[a]) + 3.0) / 8.0 + 1.0;
    check_memory(table_bytes,
                 fmt::format("the brick table of a {}x{}x{}-voxel bounding box", int64_t(index_hi[0]) - index_lo[0] + 1,
                             int64_t(index_hi[1]) - index_lo[1] + 1, int64_t(index_hi[2]) - index_lo[2] + 1),
                 file, "grid", g.metadata_.name);
    for (int a = 0; a < 3; ++a)
      if (index_lo[a] < -kMaxVoxelIndex || index_hi[a] > kMaxVoxelIndex)
        throw InputError(file, "grid", g.metadata_.name,
                         fmt::format("voxel indices [{}, {}] on axis {} exceed ±2^24: float lookups there would be "
                                     "off by whole voxels; re-centre the grid's index space",
                                     index_lo[a], index_hi[a], a));
  }
  for (int a = 0; a < 3; ++a) {
    // A trilinear stencil starting at lo - 1 already reads voxel lo, and one
    // ending at hi + 1 still reads voxel hi: the bricks cover [lo - 1, hi + 1].
    g.brick_base_[a] = empty ? 0 : 8 * floor_div8(index_lo[a] - 1);
    g.bricks_[a] = empty ? 0 : (index_hi[a] + 2 - g.brick_base_[a] + 7) / 8;
    g.brick_base_f_[a] = float(g.brick_base_[a]);
    g.extent_f_[a] = float(8 * g.bricks_[a]);
  }
  const size_t brick_count = size_t(g.bricks_[0]) * g.bricks_[1] * g.bricks_[2];
  auto brick_origin = [&](size_t b) {
    const int bx = int(b % g.bricks_[0]), by = int(b / g.bricks_[0] % g.bricks_[1]),
              bz = int(b / (size_t(g.bricks_[0]) * g.bricks_[1]));
    return Coord{g.brick_base_[0] + 8 * bx, g.brick_base_[1] + 8 * by, g.brick_base_[2] + 8 * bz};
  };

  // Slot 0 is the shared background brick; candidates get slots 1.. in order.
  g.table_.assign(brick_count, 0);
  uint32_t slots = 1;
  for (size_t b = 0; b < brick_count; ++b)
    if (may_hold_data(brick_origin(b))) g.table_[b] = slots++;
  g.pool_.assign(size_t(slots) * kBrickValues, background);

  std::atomic<int64_t> nan{0}, inf{0}, negative{0};
  InvalidExample example;
  std::vector<uint8_t> holds_data(slots, 0);
  tbb::parallel_for(size_t(0), brick_count, [&](size_t b) {
    if (g.table_[b] == 0) return;
    float* v = g.pool_.data() + size_t(g.table_[b]) * kBrickValues;
    const Coord o = brick_origin(b);
    fill(o, v);
    // Count each voxel once: as part of its own brick, not of a neighbour's apron.
    InvalidValueCounts counts;
    for (int z = 0; z < kBrickSize; ++z)
      for (int y = 0; y < kBrickSize; ++y)
        for (int x = 0; x < kBrickSize; ++x) {
          const float value = v[x + kBrickStride * (y + kBrickStride * z)];
          if (!is_invalid(value)) continue;
          count_invalid(value, &counts);
          std::lock_guard lock(example.mutex);
          if (!example.found) {
            example.found = true;
            example.where = {o[0] + x, o[1] + y, o[2] + z};
            example.value = value;
          }
        }
    if (counts.total() > 0) {
      nan += counts.nan;
      inf += counts.inf;
      negative += counts.negative;
      if (clamp_invalid)
        for (int i = 0; i < kBrickValues; ++i)
          if (is_invalid(v[i])) v[i] = 0.f;
    }
    bool differs = false;
    for (int i = 0; i < kBrickValues && !differs; ++i) differs = v[i] != background;
    holds_data[g.table_[b]] = differs;
  });

  const InvalidValueCounts invalid{nan.load(), inf.load(), negative.load()};
  if (invalid.total() > 0) {
    if (!clamp_invalid)
      throw InputError(file, "grid", g.metadata_.name,
                       fmt::format("has {} NaN, {} infinite and {} negative voxel values (first seen: voxel ({}, {}, {}) "
                                   "= {}); a concentration must be finite and >= 0 (option clamp_invalid sets them to 0)",
                                   invalid.nan, invalid.inf, invalid.negative, example.where[0], example.where[1],
                                   example.where[2], example.value));
    g.metadata_.clamped_voxels = invalid.total();
  }

  // Bricks that turned out to hold only the background go back to slot 0, and
  // the pool is compacted in slot order (slots only move down, so in place).
  std::vector<uint32_t> new_slot(slots, 0);
  uint32_t kept = 1;
  for (uint32_t s = 1; s < slots; ++s)
    if (holds_data[s]) {
      new_slot[s] = kept;
      if (kept != s)
        std::memcpy(g.pool_.data() + size_t(kept) * kBrickValues, g.pool_.data() + size_t(s) * kBrickValues,
                    kBrickValues * sizeof(float));
      ++kept;
    }
  for (uint32_t& t : g.table_) t = new_slot[t];
  g.pool_.resize(size_t(kept) * kBrickValues);
  g.pool_.shrink_to_fit();

  g.min_value_ = g.max_value_ = background;
  for (float v : g.pool_) {
    g.min_value_ = std::min(g.min_value_, v);
    g.max_value_ = std::max(g.max_value_, v);
  }
  return g;
}

VoxelGrid VoxelGrid::from_dense(const DenseGrid& dense, bool clamp_invalid) {
  const Coord lo = dense.origin;
  // The last index in int64: origin + dims overflows int for a grid ending at INT_MAX (UBSan).
  Coord hi;
  for (int a = 0; a < 3; ++a) {
    const int64_t last = int64_t(lo[a]) + dense.dims[a] - 1;
    if (last > std::numeric_limits<int>::max() || last < std::numeric_limits<int>::min())
      throw InputError("<memory>", "grid", dense.metadata.name,
                       fmt::format("voxel indices from {} over {} voxels on axis {} leave the int range", lo[a],
                                   dense.dims[a], a));
    hi[a] = int(last);
  }
  if (dense.values.size() != size_t(dense.dims[0]) * dense.dims[1] * dense.dims[2])
    throw InputError("<memory>", "grid", dense.metadata.name,
                     fmt::format("has {} values for {}x{}x{} voxels", dense.values.size(), dense.dims[0],
                                 dense.dims[1], dense.dims[2]));
  auto may_hold_data = [&](Coord o) {
    for (int a = 0; a < 3; ++a)
      if (o[a] + kBrickSize < lo[a] || o[a] > hi[a]) return false;
    return true;
  };
  auto fill = [&](Coord o, float* v) {
    for (int z = 0; z < kBrickStride; ++z)
      for (int y = 0; y < kBrickStride; ++y)
        for (int x = 0; x < kBrickStride; ++x) {
          const int i = o[0] + x - lo[0], j = o[1] + y - lo[1], k = o[2] + z - lo[2];
          const bool inside = i >= 0 && j >= 0 && k >= 0 && i < dense.dims[0] && j < dense.dims[1] && k < dense.dims[2];
          v[x + kBrickStride * (y + kBrickStride * z)] = inside ? dense.at(i, j, k) : dense.background;
        }
  };
  return from_bricks(lo, hi, dense.background, dense.world_from_index, dense.metadata, may_hold_data, fill,
                     clamp_invalid);
}

float VoxelGrid::voxel(int x, int y, int z) const {
  const int ix = x - brick_base_[0], iy = y - brick_base_[1], iz = z - brick_base_[2];
  if (ix < 0 || iy < 0 || iz < 0 || ix >= 8 * bricks_[0] || iy >= 8 * bricks_[1] || iz >= 8 * bricks_[2])
    return background_;
  return *brick_values(ix, iy, iz);
}

void VoxelGrid::copy_block(Coord lo, Coord hi, float* out) const {
  const int extent[3] = {8 * bricks_[0], 8 * bricks_[1], 8 * bricks_[2]};
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y) {
      const int iy = y - brick_base_[1], iz = z - brick_base_[2];
      const bool row_stored = iy >= 0 && iz >= 0 && iy < extent[1] && iz < extent[2];
      for (int x = lo[0]; x <= hi[0];) {
        const int ix = x - brick_base_[0];
        if (!row_stored || ix < 0 || ix >= extent[0]) {
          *out++ = background_;
          ++x;
          continue;
        }
        // The rest of this brick's row is contiguous.
        const int run = std::min(hi[0] - x + 1, 8 - (ix & 7));
        out = std::copy_n(brick_values(ix, iy, iz), run, out);
        x += run;
      }
    }
}

template <typename F>
void VoxelGrid::for_each_value(Coord lo, Coord hi, F&& f) const {
  int64_t total = 1;
  for (int a = 0; a < 3; ++a) total *= std::max<int64_t>(0, int64_t(hi[a]) - lo[a] + 1);
  if (total == 0) {  // an empty box: the background, as for a box outside the voxels
    f(background_, int64_t(0));
    return;
  }
  // Clip to the stored voxels; any part of the box outside them is background.
  Coord clo, chi;
  int64_t inside = 1;
  for (int a = 0; a < 3; ++a) {
    const int slo = brick_base_[a], shi = brick_base_[a] + 8 * bricks_[a] - 1;
    clo[a] = std::max(lo[a], slo);
    chi[a] = std::min(hi[a], shi);
    inside *= std::max<int64_t>(0, int64_t(chi[a]) - clo[a] + 1);
  }
  if (inside < total) f(background_, total - inside);
  if (inside == 0) return;
  for (int bz = (clo[2] - brick_base_[2]) >> 3; bz <= (chi[2] - brick_base_[2]) >> 3; ++bz)
    for (int by = (clo[1] - brick_base_[1]) >> 3; by <= (chi[1] - brick_base_[1]) >> 3; ++by)
      for (int bx = (clo[0] - brick_base_[0]) >> 3; bx <= (chi[0] - brick_base_[0]) >> 3; ++bx) {
        const uint32_t slot = table_[bx + bricks_[0] * (by + bricks_[1] * bz)];
        const Coord o{brick_base_[0] + 8 * bx, brick_base_[1] + 8 * by, brick_base_[2] + 8 * bz};
        const Coord a{std::max(clo[0], o[0]) - o[0], std::max(clo[1], o[1]) - o[1], std::max(clo[2], o[2]) - o[2]};
        const Coord b{std::min(chi[0], o[0] + 7) - o[0], std::min(chi[1], o[1] + 7) - o[1],
                      std::min(chi[2], o[2] + 7) - o[2]};
        if (slot == 0) {  // a background brick: no need to read its voxels
          f(background_, int64_t(b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1));
          continue;
        }
        const float* v = pool_.data() + size_t(slot) * kBrickValues;
        for (int z = a[2]; z <= b[2]; ++z)
          for (int y = a[1]; y <= b[1]; ++y)
            for (int x = a[0]; x <= b[0]; ++x) f(v[x + kBrickStride * (y + kBrickStride * z)], int64_t(1));
      }
}

std::pair<float, float> VoxelGrid::min_max(Coord lo, Coord hi) const {
  float mn = std::numeric_limits<float>::max(), mx = std::numeric_limits<float>::lowest();
  for_each_value(lo, hi, [&](float value, int64_t) {
    mn = std::min(mn, value);
    mx = std::max(mx, value);
  });
  return {mn, mx};
}

float VoxelGrid::mean(Coord lo, Coord hi) const {
  double sum = 0.0;
  int64_t count = 0;
  for_each_value(lo, hi, [&](float value, int64_t n) {
    sum += double(value) * double(n);
    count += n;
  });
  return count > 0 ? float(sum / double(count)) : background_;
}

Bounds3 VoxelGrid::index_bounds(Interpolation interpolation) const {
  Bounds3 b;
  if (index_lo_[0] > index_hi_[0] || index_lo_[1] > index_hi_[1] || index_lo_[2] > index_hi_[2]) return b;
  const Vec3 r(support_radius(interpolation));
  b.lo = Vec3{float(index_lo_[0]), float(index_lo_[1]), float(index_lo_[2])} - r;
  b.hi = Vec3{float(index_hi_[0]), float(index_hi_[1]), float(index_hi_[2])} + r;
  return b;
}

Bounds3 VoxelGrid::world_bounds(Interpolation interpolation) const {
  const Bounds3 ib = index_bounds(interpolation);
  Bounds3 wb;
  if (ib.empty()) return wb;
  for (int c = 0; c < 8; ++c)
    wb.extend(world_from_index_.point({c & 1 ? ib.hi.x : ib.lo.x, c & 2 ? ib.hi.y : ib.lo.y, c & 4 ? ib.hi.z : ib.lo.z}));
  return wb;
}

}  // namespace chlorovdb
