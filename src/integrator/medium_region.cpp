#include "integrator/medium_region.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

Bounds3 medium_region(const Scene& scene, int medium) {
  Bounds3 b;
  constexpr int kLattice = 32;
  for (int s = 0; s < int(scene.shapes.size()); ++s) {
    if (scene.shapes[size_t(s)].medium_inside != medium) continue;
    for (int i = 0; i < kLattice; ++i)
      for (int j = 0; j < kLattice; ++j)
        b.extend(scene.geometry.sample_area(s, Point2{(i + 0.5f) / kLattice, (j + 0.5f) / kLattice}).p);
  }
  return b;
}

int medium_at(const Scene& scene, const Vec3& p) {
  const Vec3 d = normalize(Vec3{0.2673f, 0.5345f, 0.8018f});  // off every axis, so box edges are not grazed
  const auto hit = scene.geometry.intersect(Ray{p, d}, kInfinity);
  if (!hit) return scene.camera_medium;
  const ShapeBinding& b = scene.shapes[size_t(hit->shape_id)];
  return dot(d, hit->ng) > 0.f ? b.medium_inside : b.medium_outside;
}

std::array<int, 3> cell_counts(const Bounds3& region, int longest) {
  const Vec3 d = region.diagonal();
  const float dmax = std::max({d.x, d.y, d.z});
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) n[size_t(a)] = std::clamp(int(std::lround(longest * d[a] / dmax)), 1, longest);
  return n;
}

}  // namespace chlorovdb
