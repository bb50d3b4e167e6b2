#pragma once
// Warping functions as sample / pdf pairs (inputs u in [0,1)).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/constants.h"
#include "core/vec.h"

namespace chlorovdb {

struct Point2 {
  float x = 0, y = 0;
};

// Free-flight distance in a medium of extinction sigma: p(t) = sigma e^{-sigma t}.
inline float sample_exponential(float u, float sigma) { return -std::log1p(-u) / sigma; }

inline Vec3 sample_uniform_sphere(Point2 u) {
  const float z = 1.f - 2.f * u.x;
  const float r = std::sqrt(std::max(0.f, 1.f - z * z));
  const float phi = 2.f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline constexpr float uniform_sphere_pdf() { return kInv4Pi; }

// Concentric (Shirley-Chiu) disk mapping: area preserving, low distortion.
inline Point2 sample_uniform_disk_concentric(Point2 u) {
  const float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
  if (ox == 0.f && oy == 0.f) return {0.f, 0.f};
  float r, theta;
  if (std::fabs(ox) > std::fabs(oy)) {
    r = ox;
    theta = 0.25f * kPi * (oy / ox);
  } else {
    r = oy;
    theta = 0.5f * kPi - 0.25f * kPi * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

// Cosine-weighted hemisphere around +z: pdf = cos(theta) / pi.
inline Vec3 sample_cosine_hemisphere(Point2 u) {
  const Point2 d = sample_uniform_disk_concentric(u);
  const float z = std::sqrt(std::max(0.f, 1.f - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}
inline float cosine_hemisphere_pdf(float cos_theta) { return cos_theta * kInvPi; }

// Cone of directions around +z with cos(theta) >= cos_max, uniform in solid angle.
inline Vec3 sample_uniform_cone(Point2 u, float cos_max) {
  const float cos_t = (1.f - u.x) + u.x * cos_max;
  const float sin_t = std::sqrt(std::max(0.f, 1.f - cos_t * cos_t));
  const float phi = u.y * 2.f * kPi;
  return {std::cos(phi) * sin_t, std::sin(phi) * sin_t, cos_t};
}
inline float uniform_cone_pdf(float cos_max) { return 1.f / (2.f * kPi * (1.f - cos_max)); }

// Barycentrics uniform over a triangle (Heitz 2019 low-distortion map).
inline std::array<float, 3> sample_uniform_triangle(Point2 u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2;
    b0 = u.x - b1;
  }
  return {b0, b1, 1 - b0 - b1};
}

// Power heuristic (beta = 2) for two strategies with nf and ng samples.
inline float power_heuristic(int nf, float f_pdf, int ng, float g_pdf) {
  const float f = nf * f_pdf, g = ng * g_pdf;
  if (std::isinf(f * f)) return 1.f;
  const float denom = f * f + g * g;
  return denom > 0.f ? (f * f) / denom : 0.f;
}

// Discrete distribution over weights with a cumulative table (for lights,
// triangles, camera wavelengths and tabulated 1-D densities). sample() starts from
// a guide table (the bin u = k / size falls in, one cell per bin) and walks to the
// bin a binary search would find: O(1) on average, where the search was O(log n)
// (the camera's 940 wavelength bins are drawn four times per camera sample).
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::span<const float> weights);
  bool empty() const { return pdf_.empty(); }
  int size() const { return int(pdf_.size()); }
  float total() const { return total_; }
  // Index i with probability pmf(i); `u_remapped` (optional) receives u rescaled to [0,1) inside the bin.
  int sample(float u, float* pmf = nullptr, float* u_remapped = nullptr) const;  // inline: per camera sample
  float pmf(int i) const { return pdf_[i]; }

 private:
  std::vector<float> pdf_;
  std::vector<double> cdf_;  // double: with thousands of bins a float CDF's bin widths drift from pdf_
  std::vector<uint32_t> guide_;  // guide_[k]: the bin u = k / size falls in
  float total_ = 0;
};

inline int Distribution1D::sample(float u, float* pmf, float* u_remapped) const {
  // The first bin whose upper edge exceeds u (cdf[i] <= u < cdf[i+1], unique for a
  // non-decreasing CDF), found from the guide's bin by walking both ways, so rounding
  // in the cell index cannot matter; then skip zero-probability bins.
  const int n = int(pdf_.size());
  const double x = double(u) * double(n);
  int i = int(guide_[x > 0 ? size_t(std::min(x, double(n - 1))) : 0]);
  while (i > 0 && cdf_[size_t(i)] > u) --i;
  while (i + 1 < n && cdf_[size_t(i) + 1] <= u) ++i;
  while (pdf_[i] == 0.f && i > 0) --i;
  if (pmf) *pmf = pdf_[i];
  if (u_remapped) {
    const double width = cdf_[i + 1] - cdf_[i];
    *u_remapped = width > 0 ? std::min(float((u - cdf_[i]) / width), 0x1.fffffep-1f) : 0.f;
  }
  return i;
}

}  // namespace chlorovdb
