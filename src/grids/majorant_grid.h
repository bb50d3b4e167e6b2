#pragma once
// MajorantGrid: coarse cells over one or more VoxelGrids ("channels"), each
// cell holding per channel the max and min of every value a lookup within a
// quarter voxel of the cell can return (points that rounding puts a hair outside
// the cell are covered too). Cell faces lie on voxel faces, so an n-voxel cell
// reads n + 2 voxels per axis. A nearest lookup can return any of them; a
// trilinear one weighs the outer layer by at most 3/4, and its bounds count it so
// (majorant_grid.cpp). An under-estimated majorant would bias tracking silently;
// tests/grids and tests/tracking check this bound.
//
// MajorantIterator walks the cells a ray crosses (3-D DDA, Amanatides & Woo)
// and yields segments in the ray's own parameter t. Runs of cells whose maxima
// are all zero come out merged as one segment. Empty space is crossed in jumps:
// each empty cell knows its Chebyshev distance r (in cells) to the nearest
// non-empty one, so the cube of half-width r - 1 around it is empty and the
// ray leaves that cube in one step. Rounding may end a jump a hair inside a
// non-empty cell; lookups there read only voxels of the empty cell's own stencil.
#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "core/vec.h"
#include "grids/voxel_grid.h"

namespace chlorovdb {

// Grids a medium samples: pigment concentrations and a particle-scattering grid.
inline constexpr int kMaxMajorantChannels = 5;

struct MajorantSegment {
  float t_min = 0.f, t_max = 0.f;  // in the parameter of the ray given to segments()
  // Per channel k: no lookup in (t_min, t_max) returns more than c_max[k] or less
  // than c_min[k]; c_mean[k] is the mean of the cell's own voxels, a prediction (not
  // a bound) of what the ray meets there. All point into the grid (valid while it
  // lives): a segment is made for every cell a ray crosses, so it copies nothing.
  const float* c_max = nullptr;
  const float* c_min = nullptr;
  const float* c_mean = nullptr;
};

class MajorantIterator;

class MajorantGrid {
 public:
  MajorantGrid() = default;  // no channels: every ray is one segment
  // The grid lives in the index space of channels[0] ("majorant index space");
  // other channels may have other transforms (their bounds are then taken over
  // each cell's bounding box in their own index space). Cells are cubes of
  // voxels_per_cell voxels of channels[0] and cover every channel's support.
  // The bounds hold for lookups with `interpolation`.
  MajorantGrid(std::span<const VoxelGrid* const> channels, int voxels_per_cell, Interpolation interpolation);

  // Segments covering [0, t_max] of a ray given in majorant index space.
  inline MajorantIterator segments(const Ray& ray_index, float t_max) const;

  int channels() const { return channels_; }
  Coord resolution() const { return res_; }
  int voxels_per_cell() const { return voxels_per_cell_; }
  // The region the cells cover, in majorant index space; outside it every channel is its background.
  Bounds3 index_bounds() const;
  float cell_max(Coord cell, int channel) const { return bounds_[cell_index(cell) * stride() + channel]; }
  float cell_min(Coord cell, int channel) const { return bounds_[cell_index(cell) * stride() + channels_ + channel]; }
  float cell_mean(Coord cell, int channel) const { return bounds_[cell_index(cell) * stride() + 2 * channels_ + channel]; }
  size_t memory_bytes() const { return bounds_.size() * sizeof(float) + empty_radius_.size(); }
  // The work of tracking through these cells, relative (compare cell sizes over the same
  // channels), for sigma_t = sum_k sigma_per_value[k] * value_k in 1/m and voxels of
  // voxel_length m: per non-empty cell, its volume times the work per metre of a ray in
  // it, segment_cost / (mean chord: 2/3 of the edge, Cauchy) + sigma_maj, in collisions.
  // Empty cells cost nothing (the iterator merges or jumps them).
  double tracking_cost(std::span<const float> sigma_per_value, float voxel_length, float segment_cost) const;

 private:
  friend class MajorantIterator;
  void compute_empty_radii();
  int stride() const { return 3 * channels_; }
  size_t cell_index(Coord c) const { return c[0] + size_t(res_[0]) * (c[1] + size_t(res_[1]) * c[2]); }

  int channels_ = 0;
  int voxels_per_cell_ = 1;
  Coord res_{0, 0, 0};
  Vec3 origin_;                 // majorant index-space corner of cell (0,0,0)
  float inv_cell_size_ = 1.f;   // 1 / voxels_per_cell
  std::vector<float> bounds_;          // per cell: c_max[channels], c_min[channels], c_mean[channels]
  // Per cell: 0 if some channel's max is non-zero; else the Chebyshev distance in
  // cells to the nearest such cell (capped at 255; 255 too if there is none).
  std::vector<uint8_t> empty_radius_;
  // The bounds outside the cells, laid out like a cell's: c_max, c_min, c_mean.
  std::array<float, 3 * kMaxMajorantChannels> background_{};
  bool background_empty_ = true;
};

class MajorantIterator {
 public:
  MajorantIterator() = default;  // yields nothing
  MajorantIterator(const MajorantGrid* grid, const Ray& ray_index, float t_max);

  // The next segment, or nullopt once [0, t_max] is covered. Inline for the
  // common case, a non-empty cell inside the grid: a thick medium crosses many.
  std::optional<MajorantSegment> next() {
    if (stage_ == Stage::cells && !has_pending_ && grid_->empty_radius_[index_] == 0) return segment(step());
    return next_slow();
  }

 private:
  // A piece of the ray: one cell, or (cell < 0) a stretch outside the grid.
  struct Piece {
    float t0, t1;
    int64_t cell;
  };
  std::optional<MajorantSegment> next_slow();
  bool pull(Piece* piece);
  // One DDA step: the piece of the current cell, then move to the next cell.
  Piece step() {
    const int a = next_crossing_[0] < next_crossing_[1] ? (next_crossing_[0] < next_crossing_[2] ? 0 : 2)
                                                        : (next_crossing_[1] < next_crossing_[2] ? 1 : 2);
    // Rounding can put a crossing a hair behind t_: never step backwards.
    const float t_end = std::max(t_, std::min(next_crossing_[a], t_exit_));
    const Piece piece{t_, t_end, index_};
    t_ = t_end;
    cell_[a] += step_[a];
    index_ += index_step_[a];
    next_crossing_[a] += delta_t_[a];
    if (t_end >= t_exit_ || cell_[a] == stop_[a]) {
      t_exit_ = t_end;  // the stretch after the cells starts exactly where the last cell ended
      stage_ = Stage::after;
    }
    return piece;
  }
  bool empty(const Piece& p) const {
    return p.cell < 0 ? grid_->background_empty_ : grid_->empty_radius_[p.cell] > 0;
  }
  MajorantSegment segment(const Piece& p) const {
    const float* b = p.cell < 0 ? grid_->background_.data() : grid_->bounds_.data() + size_t(p.cell) * grid_->stride();
    return {p.t0, p.t1, b, b + grid_->channels_, b + 2 * grid_->channels_};
  }
  // (Re)start the DDA in the cell holding the ray at parameter t.
  void enter_cells(float t);

  const MajorantGrid* grid_ = nullptr;
  float t_max_ = 0.f;
  float t_enter_ = 0.f, t_exit_ = 0.f;  // the ray inside the cells
  enum class Stage : uint8_t { before, cells, after, done } stage_ = Stage::done;
  // DDA state, in cell coordinates.
  Ray ray_cells_;
  float inv_d_[3] = {};  // 1 / ray_cells_.d (0 on axes the ray is parallel to)
  Coord cell_{}, step_{}, stop_{};
  int64_t index_ = 0, index_step_[3] = {};  // linear index of cell_ and its change per step
  float next_crossing_[3] = {}, delta_t_[3] = {};
  float t_ = 0.f;
  Piece pending_{};
  bool has_pending_ = false;
};

inline MajorantIterator MajorantGrid::segments(const Ray& ray_index, float t_max) const {
  return MajorantIterator(this, ray_index, t_max);
}

}  // namespace chlorovdb
