#include "fluorescence/continuation_guide.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

int direction_bin(const Vec3& w) {
  const int iz = std::clamp(int((w.z + 1.f) * 0.5f * kDirectionZBins), 0, kDirectionZBins - 1);
  float phi = std::atan2(w.y, w.x);
  if (phi < 0.f) phi += 2.f * kPi;
  const int iphi = std::clamp(int(phi * (kDirectionPhiBins / (2.f * kPi))), 0, kDirectionPhiBins - 1);
  return iz * kDirectionPhiBins + iphi;
}

Vec3 direction_in_bin(int bin, Point2 u) {
  const int iz = bin / kDirectionPhiBins, iphi = bin % kDirectionPhiBins;
  // Uniform in (z, φ) inside the bin is uniform by solid angle (Archimedes).
  const float z = std::clamp(-1.f + 2.f * (float(iz) + u.x) / kDirectionZBins, -1.f, 1.f);
  const float phi = 2.f * kPi * (float(iphi) + u.y) / kDirectionPhiBins;
  const float r = std::sqrt(std::max(0.f, 1.f - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

ContinuationGuide::ContinuationGuide(const Bounds3& bounds, std::array<int, 3> cells,
                                     const std::vector<std::vector<float>>& bin_weights, float uniform_share)
    : bounds_(bounds), n_(cells), uniform_share_(std::clamp(uniform_share, 0.f, 1.f)) {
  cells_.resize(bin_weights.size());
  for (size_t c = 0; c < bin_weights.size(); ++c) {
    const auto& w = bin_weights[c];
    double total = 0;
    for (float v : w) total += (std::isfinite(v) && v > 0.f) ? v : 0.f;
    if (w.size() == size_t(kDirectionBins) && total > 0) cells_[c] = Distribution1D(w);
  }
}

int ContinuationGuide::cell_of(const Vec3& p) const {
  if (cells_.empty() || !bounds_.contains(p)) return -1;
  const Vec3 d = bounds_.diagonal();
  int idx[3];
  for (int a = 0; a < 3; ++a) {
    const float f = d[a] > 0.f ? (p[a] - bounds_.lo[a]) / d[a] : 0.f;
    idx[a] = std::clamp(int(f * float(n_[a])), 0, n_[a] - 1);
  }
  return (idx[2] * n_[1] + idx[1]) * n_[0] + idx[0];
}

const Distribution1D* ContinuationGuide::cell_distribution(const Vec3& x) const {
  const int c = cell_of(x);
  if (c < 0 || cells_[size_t(c)].empty()) return nullptr;
  return &cells_[size_t(c)];
}

float ContinuationGuide::pdf(const Vec3& x, const Vec3& w) const {
  const Distribution1D* d = cell_distribution(x);
  if (!d) return uniform_sphere_pdf();
  const float guided = d->pmf(direction_bin(w)) * (kDirectionBins * kInv4Pi);
  return uniform_share_ * uniform_sphere_pdf() + (1.f - uniform_share_) * guided;
}

DirectionSample ContinuationGuide::sample(const Vec3& x, float u_mix, Point2 u) const {
  const Distribution1D* d = cell_distribution(x);
  if (!d) return {sample_uniform_sphere(u), uniform_sphere_pdf()};
  Vec3 w;
  if (u_mix < uniform_share_) {
    w = sample_uniform_sphere(u);
  } else {
    float u_bin;
    const int bin = d->sample(u.x, nullptr, &u_bin);
    w = direction_in_bin(bin, Point2{u_bin, u.y});
  }
  return {w, pdf(x, w)};
}

}  // namespace chlorovdb
