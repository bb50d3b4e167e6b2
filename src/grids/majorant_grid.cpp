#include "grids/majorant_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <tbb/parallel_for.h>

#include "core/float_bits.h"

namespace chlorovdb {
namespace {

// Bounding box, in index space `to`, of the box b of index space `from`.
Bounds3 map_box(const Bounds3& b, const Transform& to_from_from) {
  Bounds3 r;
  for (int c = 0; c < 8; ++c)
    r.extend(to_from_from.point({c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z}));
  return r;
}

// Voxels whose value a lookup within a quarter voxel of the continuous index
// box b can read: a trilinear lookup at p reads voxels floor(p) and floor(p) + 1
// on each axis, a nearest one the closer of the two. The margin absorbs the
// rounding that puts a DDA segment's points a hair outside its cell.
constexpr float kStencilMargin = 0.25f;
void stencil_voxels(const Bounds3& b, Coord* lo, Coord* hi) {
  for (int a = 0; a < 3; ++a) {
    (*lo)[a] = int(std::floor(b.lo[a] - kStencilMargin));
    (*hi)[a] = int(std::floor(b.hi[a] + kStencilMargin)) + 1;
  }
}

// Min and max of every value a trilinear lookup within kStencilMargin of the voxels
// lo..hi (the box [lo - 1/2, hi + 1/2]) returns. Between voxel centres the interpolant is
// multilinear, so its extremes over the box lie at centres inside it or on its faces,
// and a face value blends an outer voxel (weight 1/2 + margin) with its inner
// neighbour, axis by axis. Counting the outer layer whole instead, as a nearest lookup
// needs, lets it set the majorant wherever the field rises toward a cell's face.
// Blended in double, rounded outward to float.
std::pair<float, float> trilinear_min_max(const VoxelGrid& g, Coord lo, Coord hi) {
  static_assert(kStencilMargin < 0.5f, "a face value blends the outer voxel with its inner neighbour only");
  const int n[3] = {hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3};
  // Cells are built in parallel: each thread reuses its blocks.
  thread_local std::vector<float> values;
  thread_local std::vector<double> v;
  values.resize(size_t(n[0]) * n[1] * n[2]);
  g.copy_block({lo[0] - 1, lo[1] - 1, lo[2] - 1}, {hi[0] + 1, hi[1] + 1, hi[2] + 1}, values.data());
  v.assign(values.begin(), values.end());
  const double outer = 0.5 + double(kStencilMargin), inner = 0.5 - double(kStencilMargin);
  const size_t stride[3] = {1, size_t(n[0]), size_t(n[0]) * n[1]};
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;  // the two other axes
    for (int j = 0; j < n[c]; ++j)
      for (int i = 0; i < n[b]; ++i) {
        double* row = &v[i * stride[b] + j * stride[c]];
        const size_t last = size_t(n[a] - 1) * stride[a];
        row[0] = outer * row[0] + inner * row[stride[a]];
        row[last] = outer * row[last] + inner * row[last - stride[a]];
      }
  }
  const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
  float lo_f = float(*mn), hi_f = float(*mx);
  if (double(lo_f) > *mn) lo_f = next_float_down(lo_f);
  if (double(hi_f) < *mx) hi_f = next_float_up(hi_f);
  return {lo_f, hi_f};
}

}  // namespace

MajorantGrid::MajorantGrid(std::span<const VoxelGrid* const> channels, int voxels_per_cell,
                           Interpolation interpolation)
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
    background_[k] = background_[channels_ + k] = background_[2 * channels_ + k] = channels[k]->background();
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
  // Cell faces on voxel faces (half-integers): a cell of n voxels then reads
  // n + 2 voxels per axis, and the margin never reaches a third.
  for (int a = 0; a < 3; ++a) {
    origin_[a] = std::floor(support.lo[a]) - 0.5f;
    res_[a] = std::max(1, int(std::ceil((support.hi[a] - origin_[a]) / float(voxels_per_cell))));
  }

  const size_t cells = size_t(res_[0]) * res_[1] * res_[2];
  bounds_.resize(cells * stride());
  empty_radius_.resize(cells);
  tbb::parallel_for(size_t(0), cells, [&](size_t i) {
    const Coord c{int(i % res_[0]), int(i / res_[0] % res_[1]), int(i / (size_t(res_[0]) * res_[1]))};
    const Vec3 lo = origin_ + Vec3(float(c[0]), float(c[1]), float(c[2])) * float(voxels_per_cell);
    const Bounds3 cell{lo, lo + Vec3(float(voxels_per_cell))};
    bool empty = true;
    for (int k = 0; k < channels_; ++k) {
      const Bounds3 box = same_space[k] ? cell : map_box(cell, channel_from_majorant[k]);
      // The voxels whose centres lie in the cell (its faces are on voxel faces).
      Coord olo, ohi;
      for (int a = 0; a < 3; ++a) {
        olo[a] = int(std::ceil(box.lo[a]));
        ohi[a] = std::max(olo[a], int(std::floor(box.hi[a])));
      }
      // Nearest lookups, and cells of another grid's space (a rotated box there): the
      // voxels of the stencil bound them.
      Coord vlo, vhi;
      stencil_voxels(box, &vlo, &vhi);
      auto [mn, mx] = channels[k]->min_max(vlo, vhi);
      // A uniform stencil (empty space, most of a sparse grid) bounds itself exactly.
      if (interpolation == Interpolation::trilinear && same_space[k] && mn < mx)
        std::tie(mn, mx) = trilinear_min_max(*channels[k], olo, ohi);
      bounds_[i * stride() + k] = mx;
      bounds_[i * stride() + channels_ + k] = mn;
      bounds_[i * stride() + 2 * channels_ + k] = channels[k]->mean(olo, ohi);
      if (mx != 0.f) empty = false;
    }
    empty_radius_[i] = empty ? 255 : 0;
  });
  compute_empty_radii();
}

// Multi-source breadth-first search from the non-empty cells over the 26
// neighbours: the number of steps is exactly the Chebyshev distance.
void MajorantGrid::compute_empty_radii() {
  std::vector<int64_t> frontier, next;
  for (size_t i = 0; i < empty_radius_.size(); ++i)
    if (empty_radius_[i] == 0) frontier.push_back(int64_t(i));
  for (int r = 1; r < 255 && !frontier.empty(); ++r) {
    next.clear();
    for (const int64_t i : frontier) {
      const Coord c{int(i % res_[0]), int(i / res_[0] % res_[1]), int(i / (int64_t(res_[0]) * res_[1]))};
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const Coord n{c[0] + dx, c[1] + dy, c[2] + dz};
            if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= res_[0] || n[1] >= res_[1] || n[2] >= res_[2]) continue;
            uint8_t& radius = empty_radius_[cell_index(n)];
            if (radius == 255) {
              radius = uint8_t(r);
              next.push_back(int64_t(cell_index(n)));
            }
          }
    }
    std::swap(frontier, next);
  }
}

double MajorantGrid::tracking_cost(std::span<const float> sigma_per_value, float voxel_length,
                                  float segment_cost) const {
  const double edge = double(voxels_per_cell_) * voxel_length;
  const double per_segment = segment_cost / (2.0 / 3.0 * edge);
  double cost = 0.0;
  for (size_t i = 0; i < empty_radius_.size(); ++i) {
    if (empty_radius_[i] != 0) continue;
    double sigma_maj = 0.0;
    for (int k = 0; k < channels_; ++k) sigma_maj += double(sigma_per_value[k]) * bounds_[i * stride() + k];
    cost += per_segment + sigma_maj;
  }
  return cost * edge * edge * edge;
}

Bounds3 MajorantGrid::index_bounds() const {
  if (res_[0] == 0) return {};
  return {origin_, origin_ + Vec3(float(res_[0]), float(res_[1]), float(res_[2])) * float(voxels_per_cell_)};
}

MajorantIterator::MajorantIterator(const MajorantGrid* grid, const Ray& ray_index, float t_max)
    : grid_(grid), t_max_(t_max), stage_(Stage::before) {
  // Cell coordinates: the parameter t is the same in both spaces.
  const float s = grid->inv_cell_size_;
  ray_cells_ = Ray{(ray_index.o - grid->origin_) * s, ray_index.d * s};
  const Bounds3 box{{0, 0, 0}, {float(grid->res_[0]), float(grid->res_[1]), float(grid->res_[2])}};
  if (grid->res_[0] == 0 || !intersect_bounds(box, ray_cells_, t_max, &t_enter_, &t_exit_)) {
    t_enter_ = t_exit_ = t_max;  // the whole ray is one stretch outside the cells
    return;
  }
  const int64_t stride[3] = {1, grid->res_[0], int64_t(grid->res_[0]) * grid->res_[1]};
  for (int a = 0; a < 3; ++a) {
    const float d = ray_cells_.d[a];
    // Axis-parallel rays never cross a plane of that axis.
    step_[a] = d > 0.f ? 1 : (d < 0.f ? -1 : 0);
    stop_[a] = d > 0.f ? grid->res_[a] : (d < 0.f ? -1 : -2);
    inv_d_[a] = d != 0.f ? 1.f / d : 0.f;
    delta_t_[a] = std::fabs(inv_d_[a]);
    index_step_[a] = step_[a] * stride[a];
  }
  enter_cells(t_enter_);
}

void MajorantIterator::enter_cells(float t) {
  t_ = t;
  const Vec3 p = ray_cells_.at(t);
  for (int a = 0; a < 3; ++a) {
    // Truncation, not std::floor (a call-sized sequence without SSE4.1): they differ
    // only below 0, where the clamp gives 0 either way. p lies in the cells, up to rounding.
    cell_[a] = std::clamp(int(p[a]), 0, grid_->res_[a] - 1);
    if (step_[a] > 0) next_crossing_[a] = t + (float(cell_[a] + 1) - p[a]) * inv_d_[a];
    else if (step_[a] < 0) next_crossing_[a] = t + (float(cell_[a]) - p[a]) * inv_d_[a];
    else next_crossing_[a] = 3e38f;
  }
  index_ = int64_t(grid_->cell_index(cell_));
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
      const int64_t index = index_;
      // Leave the empty cube of half-width r - 1 around this cell in one step.
      // A jump restarts the DDA, which costs about what two or three ordinary
      // steps do, so only jump when the cube reaches at least two cells ahead.
      if (const int r = grid_->empty_radius_[index]; r >= 3) {
        float t_jump = t_exit_;
        for (int a = 0; a < 3; ++a) {
          if (step_[a] == 0) continue;
          const float face = float(step_[a] > 0 ? cell_[a] + r : cell_[a] - r + 1);
          t_jump = std::min(t_jump, (face - ray_cells_.o[a]) * inv_d_[a]);
        }
        if (t_jump > t_) {  // else rounding left no room: take an ordinary step
          *piece = {t_, t_jump, index};
          if (t_jump >= t_exit_) {
            t_exit_ = t_jump;
            stage_ = Stage::after;
          } else {
            enter_cells(t_jump);
          }
          return true;
        }
      }
      *piece = step();
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

std::optional<MajorantSegment> MajorantIterator::next_slow() {
  Piece p;
  if (has_pending_) {
    p = pending_;
    has_pending_ = false;
  } else if (!pull(&p)) {
    return std::nullopt;
  }
  if (!empty(p)) return segment(p);
  // Merge the run of empty pieces that starts here; keep the piece that ends it for next time.
  Piece q;
  while (pull(&q)) {
    if (!empty(q)) {
      pending_ = q;
      has_pending_ = true;
      break;
    }
    p.t1 = q.t1;
  }
  return segment(p);  // empty pieces all hold zeros: any piece of the run describes it
}

}  // namespace chlorovdb
