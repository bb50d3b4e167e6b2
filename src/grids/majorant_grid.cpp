#include "grids/majorant_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/parallel_for.h>

namespace chlorovdb {
namespace {

// Bounding box, in index space `to`, of the box b of index space `from`.
Bounds3 map_box(const Bounds3& b, const Transform& to_from_from) {
  Bounds3 r;
  for (int c = 0; c < 8; ++c)
    r.extend(to_from_from.point({c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z}));
  return r;
}

// Voxels whose value a lookup anywhere in the continuous index box b can read,
// dilated by one voxel.
void stencil_voxels(const Bounds3& b, Coord* lo, Coord* hi) {
  for (int a = 0; a < 3; ++a) {
    (*lo)[a] = int(std::floor(b.lo[a])) - 1;
    (*hi)[a] = int(std::ceil(b.hi[a])) + 1;
  }
}

}  // namespace

MajorantGrid::MajorantGrid(std::span<const VoxelGrid* const> channels, int voxels_per_cell)
    : channels_(int(channels.size())), voxels_per_cell_(voxels_per_cell), inv_cell_size_(1.f / float(voxels_per_cell)) {
  if (channels.empty()) return;
  if (channels.size() > size_t(kMaxMajorantChannels))
    throw std::invalid_argument("MajorantGrid: more grids than kMaxMajorantChannels");
  if (voxels_per_cell < 1) throw std::invalid_argument("MajorantGrid: voxels_per_cell must be >= 1");

  // channel index space <- majorant index space (= channels[0]'s index space)
  std::vector<Transform> channel_from_majorant(channels.size());
  std::vector<bool> same_space(channels.size());
  for (size_t k = 0; k < channels.size(); ++k) {
    channel_from_majorant[k] = channels[k]->index_from_world() * channels[0]->world_from_index();
    same_space[k] = channel_from_majorant[k].is_identity();
    background_[k] = channels[k]->background();
    if (background_[k] != 0.f) background_empty_ = false;
  }

  // Cover each channel's support: beyond voxel lo - 1 and hi + 1 every lookup
  // is background. One more voxel of margin, so that a point rounding puts a hair
  // inside the support while the DDA has it outside still sees only background.
  Bounds3 support;
  for (size_t k = 0; k < channels.size(); ++k) {
    const VoxelGrid& g = *channels[k];
    const Coord lo = g.index_lo(), hi = g.index_hi();
    if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]) continue;
    const Bounds3 s{{float(lo[0] - 2), float(lo[1] - 2), float(lo[2] - 2)},
                    {float(hi[0] + 2), float(hi[1] + 2), float(hi[2] + 2)}};
    support.extend(map_box(s, channel_from_majorant[k].inverse()));
  }
  if (support.empty()) return;
  for (int a = 0; a < 3; ++a) {
    origin_[a] = std::floor(support.lo[a]);
    res_[a] = std::max(1, int(std::ceil((support.hi[a] - origin_[a]) / float(voxels_per_cell))));
  }

  const size_t cells = size_t(res_[0]) * res_[1] * res_[2];
  bounds_.resize(cells * stride());
  empty_.resize(cells);
  tbb::parallel_for(size_t(0), cells, [&](size_t i) {
    const Coord c{int(i % res_[0]), int(i / res_[0] % res_[1]), int(i / (size_t(res_[0]) * res_[1]))};
    const Vec3 lo = origin_ + Vec3(float(c[0]), float(c[1]), float(c[2])) * float(voxels_per_cell);
    const Bounds3 cell{lo, lo + Vec3(float(voxels_per_cell))};
    bool empty = true;
    for (int k = 0; k < channels_; ++k) {
      Coord vlo, vhi;
      stencil_voxels(same_space[k] ? cell : map_box(cell, channel_from_majorant[k]), &vlo, &vhi);
      const auto [mn, mx] = channels[k]->min_max(vlo, vhi);
      bounds_[i * stride() + k] = mx;
      bounds_[i * stride() + channels_ + k] = mn;
      if (mx != 0.f) empty = false;
    }
    empty_[i] = empty;
  });
}

Bounds3 MajorantGrid::index_bounds() const {
  if (res_[0] == 0) return {};
  return {origin_, origin_ + Vec3(float(res_[0]), float(res_[1]), float(res_[2])) * float(voxels_per_cell_)};
}

MajorantIterator::MajorantIterator(const MajorantGrid* grid, const Ray& ray_index, float t_max)
    : grid_(grid), t_max_(t_max), stage_(Stage::before) {
  // Cell coordinates: the parameter t is the same in both spaces.
  const float s = grid->inv_cell_size_;
  const Ray r{(ray_index.o - grid->origin_) * s, ray_index.d * s};
  const Bounds3 box{{0, 0, 0}, {float(grid->res_[0]), float(grid->res_[1]), float(grid->res_[2])}};
  if (grid->res_[0] == 0 || !intersect_bounds(box, r, t_max, &t_enter_, &t_exit_)) {
    t_enter_ = t_exit_ = t_max;  // the whole ray is one stretch outside the cells
    return;
  }
  t_ = t_enter_;
  const Vec3 p = r.at(t_enter_);
  for (int a = 0; a < 3; ++a) {
    cell_[a] = std::clamp(int(std::floor(p[a])), 0, grid->res_[a] - 1);
    if (r.d[a] > 0.f) {
      next_crossing_[a] = t_enter_ + (float(cell_[a] + 1) - p[a]) / r.d[a];
      delta_t_[a] = 1.f / r.d[a];
      step_[a] = 1;
      stop_[a] = grid->res_[a];
    } else if (r.d[a] < 0.f) {
      next_crossing_[a] = t_enter_ + (float(cell_[a]) - p[a]) / r.d[a];
      delta_t_[a] = -1.f / r.d[a];
      step_[a] = -1;
      stop_[a] = -1;
    } else {  // axis-parallel: never crosses a plane of this axis
      next_crossing_[a] = 3e38f;
      delta_t_[a] = 0.f;
      step_[a] = 0;
      stop_[a] = -2;
    }
  }
}

bool MajorantIterator::pull(Piece* piece) {
  switch (stage_) {
    case Stage::before:
      stage_ = t_enter_ < t_exit_ ? Stage::cells : Stage::after;
      if (t_enter_ > 0.f) {
        *piece = {0.f, t_enter_, -1};
        return true;
      }
      return pull(piece);
    case Stage::cells: {
      const int a = next_crossing_[0] < next_crossing_[1] ? (next_crossing_[0] < next_crossing_[2] ? 0 : 2)
                                                          : (next_crossing_[1] < next_crossing_[2] ? 1 : 2);
      // Rounding can put a crossing a hair behind t_: never step backwards.
      const float t_end = std::max(t_, std::min(next_crossing_[a], t_exit_));
      *piece = {t_, t_end, int64_t(grid_->cell_index(cell_))};
      t_ = t_end;
      cell_[a] += step_[a];
      next_crossing_[a] += delta_t_[a];
      if (t_end >= t_exit_ || cell_[a] == stop_[a]) {
        t_exit_ = t_end;  // the stretch after the cells starts exactly where the last cell ended
        stage_ = Stage::after;
      }
      return true;
    }
    case Stage::after:
      stage_ = Stage::done;
      if (t_exit_ < t_max_) {
        *piece = {t_exit_, t_max_, -1};
        return true;
      }
      return false;
    case Stage::done:
      return false;
  }
  return false;
}

MajorantSegment MajorantIterator::segment(const Piece& p) const {
  MajorantSegment s;
  s.t_min = p.t0;
  s.t_max = p.t1;
  const int n = grid_->channels_;
  if (p.cell < 0) {
    for (int k = 0; k < n; ++k) s.c_max[k] = s.c_min[k] = grid_->background_[k];
  } else {
    const float* b = grid_->bounds_.data() + size_t(p.cell) * grid_->stride();
    for (int k = 0; k < n; ++k) {
      s.c_max[k] = b[k];
      s.c_min[k] = b[n + k];
    }
  }
  return s;
}

std::optional<MajorantSegment> MajorantIterator::next() {
  Piece p;
  if (pending_) {
    p = *pending_;
    pending_.reset();
  } else if (!pull(&p)) {
    return std::nullopt;
  }
  if (!empty(p)) return segment(p);
  // Merge the run of empty pieces that starts here; keep the piece that ends it for next time.
  Piece q;
  while (pull(&q)) {
    if (!empty(q)) {
      pending_ = q;
      break;
    }
    p.t1 = q.t1;
  }
  return segment(p);  // empty pieces all hold zeros: any piece of the run describes it
}

}  // namespace chlorovdb
