#include "core/transform.h"

#include <cmath>
#include <stdexcept>

#include "core/constants.h"

namespace chlorovdb {
namespace {

using Mat = Transform::Mat;

Mat identity() {
  Mat m{};
  for (int i = 0; i < 4; ++i) m[i][i] = 1.f;
  return m;
}

Mat multiply(const Mat& a, const Mat& b) {
  Mat r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += double(a[i][k]) * b[k][j];
      r[i][j] = float(s);
    }
  return r;
}

Mat transpose(const Mat& m) {
  Mat r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r[i][j] = m[j][i];
  return r;
}

// Gauss-Jordan elimination with partial pivoting, in double.
bool invert(const Mat& m, Mat* out) {
  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 8; ++j) a[i][j] = j < 4 ? m[i][j] : (j - 4 == i ? 1.0 : 0.0);
  for (int c = 0; c < 4; ++c) {
    int p = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[p][c])) p = r;
    if (std::fabs(a[p][c]) < 1e-30) return false;
    for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[p][j]);
    const double inv = 1.0 / a[c][c];
    for (int j = 0; j < 8; ++j) a[c][j] *= inv;
    for (int r = 0; r < 4; ++r)
      if (r != c) {
        const double f = a[r][c];
        for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
      }
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) (*out)[i][j] = float(a[i][j + 4]);
  return true;
}

}  // namespace

Transform::Transform() : m_(identity()), m_inv_(identity()) {}

Transform Transform::from_matrix(const Mat& m) {
  Mat inv;
  if (!invert(m, &inv)) throw std::domain_error("transform matrix is singular");
  return {m, inv};
}

Transform Transform::translate(const Vec3& t) {
  Mat m = identity(), mi = identity();
  for (int i = 0; i < 3; ++i) {
    m[i][3] = t[i];
    mi[i][3] = -t[i];
  }
  return {m, mi};
}

Transform Transform::scale(const Vec3& s) {
  if (s.x == 0.f || s.y == 0.f || s.z == 0.f) throw std::domain_error("scale has a zero component");
  Mat m = identity(), mi = identity();
  for (int i = 0; i < 3; ++i) {
    m[i][i] = s[i];
    mi[i][i] = 1.f / s[i];
  }
  return {m, mi};
}

Transform Transform::rotate(float degrees, const Vec3& axis) {
  const Vec3 a = normalize(axis);
  const float th = degrees * kPi / 180.f, s = std::sin(th), c = std::cos(th);
  Mat m = identity();
  m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
  m[0][1] = a.x * a.y * (1 - c) - a.z * s;
  m[0][2] = a.x * a.z * (1 - c) + a.y * s;
  m[1][0] = a.x * a.y * (1 - c) + a.z * s;
  m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
  m[1][2] = a.y * a.z * (1 - c) - a.x * s;
  m[2][0] = a.x * a.z * (1 - c) - a.y * s;
  m[2][1] = a.y * a.z * (1 - c) + a.x * s;
  m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
  return {m, transpose(m)};  // rotations are orthogonal
}

Transform Transform::look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 dir = normalize(target - eye);
  if (!(length(up) > 0.f) || !is_finite(up)) throw std::domain_error("look_at: 'up' must be a non-zero, finite vector");
  if (!is_finite(dir)) throw std::domain_error("look_at: the view direction is not finite (eye and target too far apart)");
  // Nearly parallel vectors give a frame dominated by rounding: refuse below ~0.00006 degrees.
  const Vec3 c = cross(normalize(up), dir);
  if (!(length(c) > 1e-6f)) throw std::domain_error("look_at: 'up' is parallel to the view direction");
  const Vec3 right = normalize(c);
  const Vec3 new_up = cross(dir, right);
  Mat m = identity();  // columns: right, up, dir, eye (camera looks down +z)
  for (int i = 0; i < 3; ++i) {
    m[i][0] = right[i];
    m[i][1] = new_up[i];
    m[i][2] = dir[i];
    m[i][3] = eye[i];
  }
  return from_matrix(m);
}

Vec3 Transform::normal(const Vec3& n) const {
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = m_inv_[0][i] * n.x + m_inv_[1][i] * n.y + m_inv_[2][i] * n.z;
  return r;
}

Transform Transform::operator*(const Transform& rhs) const {
  return {multiply(m_, rhs.m_), multiply(rhs.m_inv_, m_inv_)};
}

bool Transform::is_identity() const { return m_ == identity(); }

}  // namespace chlorovdb
