#include <gtest/gtest.h>

#include "core/transform.h"

using namespace chlorovdb;

TEST(Transform, InverseRoundTrip) {
  const Transform t = Transform::translate({1, 2, 3}) * Transform::rotate(30, {0, 1, 1}) * Transform::scale({2, 0.5f, 4});
  const Vec3 p{0.3f, -1.2f, 5.f};
  const Vec3 q = t.inverse().point(t.point(p));
  EXPECT_NEAR(q.x, p.x, 1e-5f);
  EXPECT_NEAR(q.y, p.y, 1e-5f);
  EXPECT_NEAR(q.z, p.z, 1e-5f);
}

TEST(Transform, NormalsStayPerpendicularUnderNonUniformScale) {
  const Transform t = Transform::scale({1, 4, 1});
  const Vec3 tangent = t.vector(normalize(Vec3{1, 1, 0}));
  const Vec3 n = t.normal(normalize(Vec3{1, -1, 0}));
  EXPECT_NEAR(dot(tangent, n), 0.f, 1e-6f);
}

TEST(Transform, SingularMatrixIsRejected) {
  EXPECT_THROW(Transform::scale({1, 0, 1}), std::domain_error);
}
