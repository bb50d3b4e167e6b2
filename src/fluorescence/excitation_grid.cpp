#include "fluorescence/excitation_grid.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

namespace {
constexpr float kBinWidth = (kLambdaMax - kLambdaMinUV) / float(ExcitationGrid::kBins);
}

int ExcitationGrid::bin_of(float lambda_nm) {
  return std::clamp(int((lambda_nm - kLambdaMinUV) / kBinWidth), 0, kBins - 1);
}

float ExcitationGrid::bin_center(int bin) { return kLambdaMinUV + (float(bin) + 0.5f) * kBinWidth; }

ExcitationGrid::ExcitationGrid(const Bounds3& region, const std::array<int, 3>& cells)
    : region_(region), n_(cells) {
  const Vec3 d = region.diagonal();
  cell_size_ = Vec3{d.x / float(n_[0]), d.y / float(n_[1]), d.z / float(n_[2])};
  medium_volume_.assign(size_t(n_[0]) * size_t(n_[1]) * size_t(n_[2]), 0.f);
  values_.assign(medium_volume_.size() * kBins, 0.f);
}

// Amanatides–Woo traversal: add_length(cell, length) for every cell the segment a→b crosses.
template <typename F>
void ExcitationGrid::for_each_cell(const Vec3& a, const Vec3& b, F add_length) const {
  const float length = distance(a, b);
  if (!(length > 0.f)) return;
  const Ray ray{a, (b - a) / length};
  float t0, t1;
  if (!intersect_bounds(region_, ray, length, &t0, &t1)) return;
  const Vec3 start = ray.at(t0 + 1e-4f * (t1 - t0));  // inside the first cell, not on its face
  std::array<int, 3> cell{}, step{};
  std::array<float, 3> t_next{}, t_delta{};
  for (int k = 0; k < 3; ++k) {
    cell[k] = std::clamp(int((start[k] - region_.lo[k]) / cell_size_[k]), 0, n_[k] - 1);
    const float dk = ray.d[k];
    if (dk > 0.f) {
      step[k] = 1;
      t_next[k] = (region_.lo[k] + float(cell[k] + 1) * cell_size_[k] - ray.o[k]) / dk;
      t_delta[k] = cell_size_[k] / dk;
    } else if (dk < 0.f) {
      step[k] = -1;
      t_next[k] = (region_.lo[k] + float(cell[k]) * cell_size_[k] - ray.o[k]) / dk;
      t_delta[k] = -cell_size_[k] / dk;
    } else {
      step[k] = 0;
      t_next[k] = kInfinity;
      t_delta[k] = kInfinity;
    }
  }
  float t = t0;
  while (t < t1) {
    const int k = t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
    const float t_exit = std::min(t_next[k], t1);
    if (t_exit > t) add_length(size_t(cell_index(cell[0], cell[1], cell[2])), t_exit - t);
    t = t_exit;
    cell[k] += step[k];
    if (cell[k] < 0 || cell[k] >= n_[k]) break;
    t_next[k] += t_delta[k];
  }
}

void ExcitationGrid::deposit(const Vec3& a, const Vec3& b, int bin, float value_per_length) {
  if (!(value_per_length > 0.f)) return;
  for_each_cell(a, b, [&](size_t cell, float length) { values_[cell * kBins + size_t(bin)] += value_per_length * length; });
}

void ExcitationGrid::add_medium_volume(const Vec3& a, const Vec3& b, float cross_section) {
  for_each_cell(a, b, [&](size_t cell, float length) { medium_volume_[cell] += cross_section * length; });
}

double ExcitationGrid::cell_total(size_t cell) const {
  double sum = 0;
  for (int b = 0; b < kBins; ++b) sum += values_[cell * kBins + size_t(b)];
  return sum;
}

void ExcitationGrid::set_tally_errors(std::vector<float> errors) {
  errors_ = std::move(errors);
  double variance = 0, square = 0;
  for (size_t c = 0; c < errors_.size() && c < cell_count(); ++c) {
    const double total = cell_total(c);
    variance += double(errors_[c]) * errors_[c];
    square += total * total;
  }
  relative_error_ = square > 0 ? float(std::sqrt(variance / square)) : 0.f;
}

void ExcitationGrid::add(const ExcitationGrid& other) {
  for (size_t i = 0; i < values_.size(); ++i) values_[i] += other.values_[i];
  for (size_t i = 0; i < medium_volume_.size(); ++i) medium_volume_[i] += other.medium_volume_[i];
}

void ExcitationGrid::normalize(double photons) {
  const double cell = cell_volume();
  for (size_t c = 0; c < medium_volume_.size(); ++c) {
    // A cell the lines found no medium in but a photon did (a sliver between
    // lines) is taken as full: its tally is small either way.
    const double volume = medium_volume_[c] > 0.f ? std::min(double(medium_volume_[c]), cell) : cell;
    for (int b = 0; b < kBins; ++b) values_[c * kBins + size_t(b)] = float(values_[c * kBins + size_t(b)] / (photons * volume));
    if (c < errors_.size()) errors_[c] = float(errors_[c] / (photons * volume));
  }
}

const float* ExcitationGrid::at(const Vec3& x) const {
  if (values_.empty() || !region_.contains(x)) return nullptr;
  std::array<int, 3> c{};
  for (int k = 0; k < 3; ++k) c[k] = std::clamp(int((x[k] - region_.lo[k]) / cell_size_[k]), 0, n_[k] - 1);
  return &values_[size_t(cell_index(c[0], c[1], c[2])) * kBins];
}

}  // namespace chlorovdb
