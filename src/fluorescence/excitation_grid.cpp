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

ExcitationGrid::ExcitationGrid(const Bounds3& region, const std::array<int, 3>& cells, Measure measure)
    : region_(region), n_(cells), measure_(measure) {
  const Vec3 d = region.diagonal();
  cell_size_ = Vec3{d.x / float(n_[0]), d.y / float(n_[1]), d.z / float(n_[2])};
  medium_volume_.assign(size_t(n_[0]) * size_t(n_[1]) * size_t(n_[2]), 0.f);
  values_.assign(medium_volume_.size() * kBins, 0.f);
  tally_moment_.assign(medium_volume_.size(), Vec3(0.f));
  medium_moment_.assign(medium_volume_.size(), Vec3(0.f));
  medium_spread_.assign(medium_volume_.size(), Vec3(0.f));
  medium_lo_.assign(medium_volume_.size(), Vec3(kInfinity));
  medium_hi_.assign(medium_volume_.size(), Vec3(-kInfinity));
}

Vec3 ExcitationGrid::cell_center(const std::array<int, 3>& c) const {
  return region_.lo + Vec3{(float(c[0]) + 0.5f) * cell_size_.x, (float(c[1]) + 0.5f) * cell_size_.y,
                           (float(c[2]) + 0.5f) * cell_size_.z};
}

Vec3 ExcitationGrid::cell_center(size_t cell) const {
  const int ix = int(cell % size_t(n_[0])), iy = int(cell / size_t(n_[0]) % size_t(n_[1])),
            iz = int(cell / (size_t(n_[0]) * size_t(n_[1])));
  return cell_center(std::array<int, 3>{ix, iy, iz});
}

size_t ExcitationGrid::cell_of(const Vec3& x) const {
  std::array<int, 3> c{};
  for (int k = 0; k < 3; ++k) c[k] = std::clamp(int((x[k] - region_.lo[k]) / cell_size_[k]), 0, n_[k] - 1);
  return size_t(cell_index(c[0], c[1], c[2]));
}

Bounds3 ExcitationGrid::cell_bounds(size_t cell) const {
  const Vec3 c = cell_center(cell);
  return Bounds3{c - 0.5f * cell_size_, c + 0.5f * cell_size_};
}

void ExcitationGrid::deposit(const Vec3& a, const Vec3& b, int bin, float value_per_length) {
  if (!(value_per_length > 0.f)) return;
  const Vec3 d = chlorovdb::normalize(b - a);
  for_each_cell(a, b, [&](size_t cell, float t0, float t1) {
    tally(cell, bin, value_per_length * (t1 - t0), a + (0.5f * (t0 + t1)) * d);
  });
}

void ExcitationGrid::add_pigment_amount(const Vec3& x, float amount, const Vec3& half) {
  if (!(amount > 0.f)) return;
  const size_t cell = cell_of(x);
  const Vec3 offset = x - cell_center(cell);
  medium_volume_[cell] += amount;
  medium_moment_[cell] += amount * offset;
  medium_spread_[cell] += amount * (mul(offset, offset) + mul(half, half) / 3.f);
  medium_lo_[cell] = min(medium_lo_[cell], offset - half);
  medium_hi_[cell] = max(medium_hi_[cell], offset + half);
}

void ExcitationGrid::add_medium_volume(const Vec3& a, const Vec3& b, float cross_section) {
  const Vec3 d = b - a;
  const float total = length(d);
  if (!(total > 0.f)) return;
  const Vec3 dir = d / total;
  for_each_cell(a, b, [&](size_t cell, float t0, float t1) {
    const float length = t1 - t0;
    const Vec3 mid = a + (0.5f * (t0 + t1)) * dir - cell_center(cell);
    const float volume = cross_section * length;
    medium_volume_[cell] += volume;
    medium_moment_[cell] += volume * mid;
    // ∫ (x − c)² along the piece: its midpoint's square plus the piece's own spread.
    const Vec3 half = 0.5f * length * dir;
    medium_spread_[cell] += volume * (mul(mid, mid) + mul(half, half) / 3.f);
    for (int k = 0; k < 3; ++k) {
      const float reach = std::abs(half[k]);
      medium_lo_[cell][k] = std::min(medium_lo_[cell][k], mid[k] - reach);
      medium_hi_[cell][k] = std::max(medium_hi_[cell][k], mid[k] + reach);
    }
  });
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
  for (size_t i = 0; i < medium_volume_.size(); ++i) {
    medium_volume_[i] += other.medium_volume_[i];
    tally_moment_[i] += other.tally_moment_[i];
    medium_moment_[i] += other.medium_moment_[i];
    medium_spread_[i] += other.medium_spread_[i];
    medium_lo_[i] = min(medium_lo_[i], other.medium_lo_[i]);
    medium_hi_[i] = max(medium_hi_[i], other.medium_hi_[i]);
  }
}

void ExcitationGrid::normalize(double photons) {
  const double cell = cell_volume();
  profiles_.assign(medium_volume_.size(), Profile{Vec3(0.f), Vec3(0.f)});
  for (size_t c = 0; c < medium_volume_.size(); ++c) {
    // A cell the lines found no medium in but a photon did (a sliver between
    // lines) is taken as full: its tally is small either way. A cell holding no
    // pigment (Measure::amount) reads 0.
    const double volume = measure_ == Measure::amount ? double(medium_volume_[c])
                          : medium_volume_[c] > 0.f   ? std::min(double(medium_volume_[c]), cell)
                                                      : cell;
    if (!(volume > 0.0)) {
      std::fill_n(values_.begin() + long(c * kBins), kBins, 0.f);
      if (c < errors_.size()) errors_[c] = 0.f;
      continue;
    }
    // The profile 1 + g·(x − μ): with T the tally and V, m, s the medium's volume
    // and moments about the centre, μ = m/V and, per axis, g = (T₁/T − μ) / (s/V − μ²):
    // the tally's centroid offset over the medium's variance.
    const double tally = cell_total(c);
    if (medium_volume_[c] > 0.f && tally > 0) {
      Profile& p = profiles_[c];
      p.centroid = medium_moment_[c] / medium_volume_[c];
      for (int k = 0; k < 3; ++k) {
        const double variance = double(medium_spread_[c][k]) / medium_volume_[c] - double(p.centroid[k]) * p.centroid[k];
        // Below a thousandth of the cell's own variance the medium is a sheet across that axis: no slope.
        if (variance > 1e-3 * cell_size_[k] * cell_size_[k] / 12.0)
          p.gradient[k] = float((tally_moment_[c][k] / tally - p.centroid[k]) / variance);
      }
      // The limiter: the profile's lowest value over the medium's extent is 1 − drop;
      // scaling g down to drop = 1 keeps it non-negative there and the mean still 1.
      float drop = 0.f;
      for (int k = 0; k < 3; ++k)
        drop += std::abs(p.gradient[k]) *
                (p.gradient[k] > 0.f ? p.centroid[k] - medium_lo_[c][k] : medium_hi_[c][k] - p.centroid[k]);
      if (drop > 1.f) p.gradient = p.gradient / drop;
    }
    for (int b = 0; b < kBins; ++b) values_[c * kBins + size_t(b)] = float(values_[c * kBins + size_t(b)] / (photons * volume));
    if (c < errors_.size()) errors_[c] = float(errors_[c] / (photons * volume));
  }
}

ExcitationGrid::Lookup ExcitationGrid::at(const Vec3& x) const {
  if (values_.empty() || !region_.contains(x)) return {};
  const size_t cell = cell_of(x);
  if (profiles_.empty()) return {&values_[cell * kBins], 1.f};
  const Profile& p = profiles_[cell];
  // Non-negative by the limiter within the medium's measured extent; beyond it
  // (between the lines that measured it) the zero guards a steep slope.
  return {&values_[cell * kBins], std::max(1.f + dot(p.gradient, x - cell_center(cell) - p.centroid), 0.f)};
}

}  // namespace chlorovdb
