#pragma once
// Affine transform stored with its inverse. Names read destination-from-source:
// `world_from_object(p)` maps an object-space point into world space.
#include <array>
#include "core/vec.h"

namespace chlorovdb {

class Transform {
 public:
  using Mat = std::array<std::array<float, 4>, 4>;
  Transform();  // identity
  Transform(const Mat& m, const Mat& m_inv) : m_(m), m_inv_(m_inv) {}
  static Transform from_matrix(const Mat& m);  // throws std::domain_error if singular
  static Transform translate(const Vec3& t);
  static Transform scale(const Vec3& s);
  static Transform rotate(float degrees, const Vec3& axis);
  static Transform look_at(const Vec3& eye, const Vec3& target, const Vec3& up);  // world_from_camera

  // Inline: tracking maps every free flight and shadow ray into grid index space.
  Vec3 point(const Vec3& p) const {
    Vec3 r;
    for (int i = 0; i < 3; ++i) r[i] = m_[i][0] * p.x + m_[i][1] * p.y + m_[i][2] * p.z + m_[i][3];
    const float w = m_[3][0] * p.x + m_[3][1] * p.y + m_[3][2] * p.z + m_[3][3];
    return w == 1.f ? r : r / w;
  }
  Vec3 vector(const Vec3& v) const {
    Vec3 r;
    for (int i = 0; i < 3; ++i) r[i] = m_[i][0] * v.x + m_[i][1] * v.y + m_[i][2] * v.z;
    return r;
  }
  Vec3 normal(const Vec3& n) const;  // uses the inverse transpose
  Transform inverse() const { return {m_inv_, m_}; }
  Transform operator*(const Transform& rhs) const;  // (a*b)(p) = a(b(p))
  const Mat& matrix() const { return m_; }
  bool is_identity() const;

 private:
  Mat m_, m_inv_;
};

}  // namespace chlorovdb
