#pragma once
// Small 3-vector value type for points, directions and normals (float: the
// precision Embree works in). Free functions, no hidden conversions.
#include <algorithm>
#include <cmath>

namespace chlorovdb {

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3(float v) : x(v), y(v), z(v) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};

constexpr Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
constexpr Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
constexpr Vec3 operator*(Vec3 a, float s) { return a *= s; }
constexpr Vec3 operator*(float s, Vec3 a) { return a *= s; }
constexpr Vec3 operator/(const Vec3& a, float s) { return a * (1.f / s); }
constexpr Vec3 mul(const Vec3& a, const Vec3& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
constexpr bool operator==(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

constexpr float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const Vec3& a) { return std::sqrt(dot(a, a)); }
constexpr float length_squared(const Vec3& a) { return dot(a, a); }
inline float distance(const Vec3& a, const Vec3& b) { return length(a - b); }
inline Vec3 normalize(const Vec3& a) { return a / length(a); }
inline Vec3 abs(const Vec3& a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }
inline Vec3 min(const Vec3& a, const Vec3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 max(const Vec3& a, const Vec3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline float max_component(const Vec3& a) { return std::max(a.x, std::max(a.y, a.z)); }
inline bool is_finite(const Vec3& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
// Flip n to lie in the hemisphere of v.
inline Vec3 face_forward(const Vec3& n, const Vec3& v) { return dot(n, v) < 0.f ? -n : n; }

struct Ray {
  Vec3 o;
  Vec3 d;  // not necessarily unit length; tracking code normalises where it needs to
  Vec3 at(float t) const { return o + d * t; }
};

struct Bounds3 {
  Vec3 lo{kBoundsEmpty, kBoundsEmpty, kBoundsEmpty};
  Vec3 hi{-kBoundsEmpty, -kBoundsEmpty, -kBoundsEmpty};
  static constexpr float kBoundsEmpty = 3.0e38f;
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void extend(const Vec3& p) { lo = min(lo, p); hi = max(hi, p); }
  void extend(const Bounds3& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
  Vec3 diagonal() const { return hi - lo; }
  Vec3 center() const { return (lo + hi) * 0.5f; }
  bool contains(const Vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};

// Slab test: the parametric interval [t0, t1] of the ray inside the box,
// clipped to [0, t_max]. Returns false when they do not overlap.
inline bool intersect_bounds(const Bounds3& b, const Ray& r, float t_max, float* t0, float* t1) {
  float lo = 0.f, hi = t_max;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.f / r.d[a];  // +-inf for axis-parallel rays: IEEE gives the right slabs
    float tn = (b.lo[a] - r.o[a]) * inv, tf = (b.hi[a] - r.o[a]) * inv;
    if (tn > tf) std::swap(tn, tf);
    if (!(tn <= tf)) tn = -3e38f, tf = 3e38f;  // NaN from 0*inf: the ray is parallel inside the slab
    lo = std::max(lo, tn);
    hi = std::min(hi, tf);
    if (lo > hi) return false;
  }
  *t0 = lo;
  *t1 = hi;
  return true;
}

// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;
  static Frame from_z(const Vec3& n) {
    const float sign = std::copysign(1.f, n.z);
    const float a = -1.f / (sign + n.z);
    const float b = n.x * n.y * a;
    return {{1.f + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
  }
  Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace chlorovdb
