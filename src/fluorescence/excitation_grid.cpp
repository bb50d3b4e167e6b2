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
  tally_moment_.assign(medium_volume_.size(), std::array<double, 3>{});
  medium_moment_.assign(medium_volume_.size(), std::array<double, 3>{});
  medium_second_.assign(medium_volume_.size(), std::array<double, 6>{});
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

template <typename AverageProfile>
void ExcitationGrid::add_measure(size_t cell, float measure, const Vec3& offset, const std::array<float, 6>& spread,
                                 AverageProfile&& average_profile) {
  if (!(measure > 0.f)) return;
  if (second_pass_) {
    if (!profiles_.empty()) {
      const Profile& p = profiles_[cell];
      profile_integral_[cell] +=
          double(measure) * std::exp(std::clamp(dot(p.rate, offset - p.centroid), -p.limit, p.limit)) * average_profile(p.rate);
    }
    return;
  }
  const double w = measure, x = offset.x, y = offset.y, z = offset.z;
  medium_volume_[cell] += w;
  const std::array<double, 3> first{x, y, z};
  const std::array<double, 6> second{x * x, y * y, z * z, x * y, x * z, y * z};
  for (size_t i = 0; i < 3; ++i) medium_moment_[cell][i] += w * first[i];
  for (size_t i = 0; i < 6; ++i) medium_second_[cell][i] += w * (second[i] + spread[i]);
}

namespace {
// sinh(x)/x, the mean of e^t over t in [−x, x].
double sinhc(double x) { return std::abs(x) < 1e-4 ? 1.0 + x * x / 6.0 : std::sinh(x) / x; }
}  // namespace

void ExcitationGrid::add_pigment_amount(const Vec3& x, float amount, const Vec3& half) {
  const size_t cell = cell_of(x);
  // A uniform box ±half: variance half²/3 per axis; the mean of an exponential over it factorises.
  const Vec3 v = mul(half, half) / 3.f;
  add_measure(cell, amount, x - cell_center(cell), {v.x, v.y, v.z, 0.f, 0.f, 0.f}, [&](const Vec3& rate) {
    return sinhc(rate.x * half.x) * sinhc(rate.y * half.y) * sinhc(rate.z * half.z);
  });
}

void ExcitationGrid::add_medium_volume(const Vec3& a, const Vec3& b, float cross_section) {
  const Vec3 d = b - a;
  const float total = length(d);
  if (!(total > 0.f)) return;
  const Vec3 dir = d / total;
  for_each_cell(a, b, [&](size_t cell, float t0, float t1) {
    const float length = t1 - t0;
    // A piece of line: its own spread is (length²/12)·dir dirᵀ.
    const float l2 = length * length / 12.f;
    add_measure(cell, cross_section * length, a + (0.5f * (t0 + t1)) * dir - cell_center(cell),
                {l2 * dir.x * dir.x, l2 * dir.y * dir.y, l2 * dir.z * dir.z, l2 * dir.x * dir.y, l2 * dir.x * dir.z,
                 l2 * dir.y * dir.z},
                [&](const Vec3& rate) { return sinhc(0.5 * double(dot(rate, dir)) * length); });
  });
}

double ExcitationGrid::cell_total(size_t cell) const {
  double sum = 0;
  for (int b = 0; b < kBins; ++b) sum += values_[cell * kBins + size_t(b)];
  return sum;
}

ExcitationGrid ExcitationGrid::sum_of_chunks(std::vector<ExcitationGrid> chunks) {
  if (chunks.empty()) return {};
  const size_t K = chunks.size();
  ExcitationGrid sum = chunks[0];
  for (size_t k = 1; k < K; ++k) sum.add(chunks[k]);
  if (K < 2) return sum;
  const size_t cells = sum.cell_count();
  sum.errors_.assign(cells, 0.f);
  sum.centroid_covariance_.assign(cells, std::array<double, 6>{});
  double variance = 0, square = 0;
  for (size_t c = 0; c < cells; ++c) {
    // The variance of a sum of K chunk tallies is K times their sample variance; the
    // centroid T₁/T's by the delta method, from the chunks' residuals T₁ₖ − (T₁/T)·Tₖ.
    const double total = sum.cell_total(c);
    double deviations = 0;
    std::array<double, 6> residuals{};  // Σₖ rₐ r_b in the order xx, yy, zz, xy, xz, yz
    for (const ExcitationGrid& chunk : chunks) {
      const double t = chunk.cell_total(c);
      deviations += (t - total / double(K)) * (t - total / double(K));
      if (!(total > 0.0)) continue;
      std::array<double, 3> r;
      for (size_t a = 0; a < 3; ++a) r[a] = chunk.tally_moment_[c][a] - sum.tally_moment_[c][a] / total * t;
      residuals[0] += r[0] * r[0], residuals[1] += r[1] * r[1], residuals[2] += r[2] * r[2];
      residuals[3] += r[0] * r[1], residuals[4] += r[0] * r[2], residuals[5] += r[1] * r[2];
    }
    sum.errors_[c] = float(std::sqrt(double(K) * deviations / double(K - 1)));
    for (size_t i = 0; i < 6; ++i)
      sum.centroid_covariance_[c][i] = total > 0.0 ? double(K) / double(K - 1) * residuals[i] / (total * total) : 0.0;
    variance += double(sum.errors_[c]) * sum.errors_[c];
    square += total * total;
  }
  sum.relative_error_ = square > 0 ? float(std::sqrt(variance / square)) : 0.f;
  return sum;
}

void ExcitationGrid::add(const ExcitationGrid& other) {
  for (size_t i = 0; i < values_.size(); ++i) values_[i] += other.values_[i];
  for (size_t i = 0; i < medium_volume_.size(); ++i) {
    medium_volume_[i] += other.medium_volume_[i];
    for (size_t k = 0; k < 3; ++k) {
      tally_moment_[i][k] += other.tally_moment_[i][k];
      medium_moment_[i][k] += other.medium_moment_[i][k];
    }
    for (size_t k = 0; k < 6; ++k) medium_second_[i][k] += other.medium_second_[i][k];
  }
}

namespace {

// The Langevin function L(x) = coth x − 1/x: the mean of s/h under the density
// ∝ exp(x·s/h) over s in [−h, h]. Odd, rising from 0 to 1.
double langevin(double x) {
  if (std::abs(x) < 1e-3) return x / 3.0 - x * x * x / 45.0;
  return 1.0 / std::tanh(x) - 1.0 / x;
}

// Its inverse on [0, 1): Cohen's Padé approximant y(3 − y²)/(1 − y²), then Newton steps.
double inverse_langevin(double y) {
  if (y < 1e-4) return 3.0 * y;
  double x = y * (3.0 - y * y) / (1.0 - y * y);
  for (int i = 0; i < 3; ++i) {
    const double s = std::sinh(x);
    const double slope = 1.0 / (x * x) - 1.0 / (s * s);
    if (!(slope > 0.0)) break;
    x -= (langevin(x) - y) / slope;
  }
  return x;
}

// The steepest profile fitted: its rate times the medium's half-width along it
// (e⁴ across the medium, room for the leaf's 2.8 e-folds across its blade), so a
// few photons' noise or a sliver of medium cannot make a cell's value sit in a
// corner of it.
constexpr double kMaxRateTimesHalfWidth = 2.0;

}  // namespace

void ExcitationGrid::normalize(double photons, const std::function<void(ExcitationGrid&)>& measure) {
  measure(*this);
  const double cell = cell_volume();
  // A ridge of 10⁻⁴ of the cell's own variance per axis, so a medium that is a sheet
  // across some direction gets no slope along it.
  const Vec3 ridge = 1e-4f * mul(cell_size_, cell_size_) / 12.f;
  profiles_.assign(medium_volume_.size(), Profile{Vec3(0.f), Vec3(0.f), 1.f});
  for (size_t c = 0; c < medium_volume_.size(); ++c) {
    const double tally = cell_total(c);
    const double w = medium_volume_[c];
    if (!(w > 0.0) || !(tally > 0.0)) continue;
    Profile& p = profiles_[c];
    // Σ and the tally's centroid offset d.
    const std::array<double, 6>& m2 = medium_second_[c];
    const std::array<double, 3> mu{medium_moment_[c][0] / w, medium_moment_[c][1] / w, medium_moment_[c][2] / w};
    p.centroid = Vec3{float(mu[0]), float(mu[1]), float(mu[2])};
    const double sxx = m2[0] / w - mu[0] * mu[0], syy = m2[1] / w - mu[1] * mu[1], szz = m2[2] / w - mu[2] * mu[2];
    const double sxy = m2[3] / w - mu[0] * mu[1], sxz = m2[4] / w - mu[0] * mu[2], syz = m2[5] / w - mu[1] * mu[2];
    const double a = sxx + ridge.x, b = syy + ridge.y, e = szz + ridge.z;
    const struct {
      double x, y, z;
    } d{tally_moment_[c][0] / tally - mu[0], tally_moment_[c][1] / tally - mu[1], tally_moment_[c][2] / tally - mu[2]};
    // g = Σ⁻¹ d by the adjugate.
    const double c00 = b * e - syz * syz, c01 = sxz * syz - sxy * e, c02 = sxy * syz - sxz * b;
    const double c11 = a * e - sxz * sxz, c12 = sxy * sxz - a * syz, c22 = a * b - sxy * sxy;
    const double det = a * c00 + sxy * c01 + sxz * c02;
    if (!(det > 0.0)) continue;
    const double gx = (c00 * d.x + c01 * d.y + c02 * d.z) / det, gy = (c01 * d.x + c11 * d.y + c12 * d.z) / det,
                 gz = (c02 * d.x + c12 * d.y + c22 * d.z) / det;
    const double g = std::sqrt(gx * gx + gy * gy + gz * gz);
    if (!(g > 0.0)) continue;
    const double ux = gx / g, uy = gy / g, uz = gz / g;
    // The photons' noise along g: a centroid offset it could give is shrunk toward
    // flat by (1 − 1/SNR²)₊, so a cell a few photons crossed reads its average.
    double shrink = 1.0;
    if (c < centroid_covariance_.size()) {
      const std::array<double, 6>& v = centroid_covariance_[c];
      const double along = d.x * ux + d.y * uy + d.z * uz;
      const double noise =
          ux * ux * v[0] + uy * uy * v[1] + uz * uz * v[2] + 2 * (ux * uy * v[3] + ux * uz * v[4] + uy * uz * v[5]);
      if (noise > 0.0) shrink = std::max(0.0, 1.0 - noise / (along * along));
    }
    if (!(shrink > 0.0)) continue;
    const double variance = ux * ux * sxx + uy * uy * syy + uz * uz * szz + 2 * (ux * uy * sxy + ux * uz * sxz + uy * uz * syz);
    if (!(variance > 0.0)) continue;
    // Along g the medium is taken as a uniform slab of half-width h with that variance:
    // the linear fit's first moment there, g·variance, is h·L(κh) for the exponential.
    const double h = std::sqrt(3.0 * variance);
    const double kappa =
        std::min(inverse_langevin(std::min(shrink * g * variance / h, 0.999)), kMaxRateTimesHalfWidth) / h;
    p.rate = Vec3{float(kappa * ux), float(kappa * uy), float(kappa * uz)};
    p.limit = float(kappa * h);
  }
  // The second pass: each profile's mean over the medium's measure, made 1.
  profile_integral_.assign(medium_volume_.size(), 0.0);
  second_pass_ = true;
  measure(*this);
  second_pass_ = false;
  for (size_t c = 0; c < medium_volume_.size(); ++c)
    if (profile_integral_[c] > 0.0) profiles_[c].scale = float(medium_volume_[c] / profile_integral_[c]);
    else profiles_[c].rate = Vec3(0.f);
  profile_integral_.clear();
  for (size_t c = 0; c < medium_volume_.size(); ++c) {
    // A cell the lines found no medium in but a photon did (a sliver between
    // lines) is taken as full: its tally is small either way. A cell with no pigment
    // (a trilinear fringe whose voxels' amounts went to the next cell) reads 0.
    const double volume = measure_ == Measure::amount ? medium_volume_[c]
                          : medium_volume_[c] > 0.0   ? std::min(medium_volume_[c], cell)
                                                      : cell;
    const double divisor = photons * volume;
    for (int b = 0; b < kBins; ++b) {
      float& v = values_[c * kBins + size_t(b)];
      v = divisor > 0.0 ? float(v / divisor) : 0.f;
    }
    if (c < errors_.size()) errors_[c] = divisor > 0.0 ? float(errors_[c] / divisor) : 0.f;
  }
}

ExcitationGrid::Lookup ExcitationGrid::at(const Vec3& x) const {
  if (values_.empty() || !region_.contains(x)) return {};
  const size_t cell = cell_of(x);
  if (profiles_.empty()) return {&values_[cell * kBins], 1.f};
  const Profile& p = profiles_[cell];
  // The exponent clamped to ± the rate times the medium's half-width along it.
  return {&values_[cell * kBins],
          p.scale * std::exp(std::clamp(dot(p.rate, x - cell_center(cell) - p.centroid), -p.limit, p.limit))};
}

}  // namespace chlorovdb
