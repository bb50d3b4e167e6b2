#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>

#include "core/float_bits.h"
#include "core/rng.h"
#include "test_seed.h"

using namespace chlorovdb;

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();

// Bitwise equality: distinguishes -0 from +0.
void expect_same(float a, float b) { EXPECT_EQ(std::bit_cast<uint32_t>(a), std::bit_cast<uint32_t>(b)) << a << " " << b; }
}  // namespace

TEST(FloatBits, MatchNextafterOnSpecialValues) {
  const float max = std::numeric_limits<float>::max(), den = std::numeric_limits<float>::denorm_min();
  for (const float v : {0.f, -0.f, den, -den, 1.f, -1.f, max, -max, kInf, -kInf, 1e-38f, -1e-38f}) {
    expect_same(next_float_up(v), std::nextafter(v, kInf));
    expect_same(next_float_down(v), std::nextafter(v, -kInf));
  }
  EXPECT_TRUE(std::isnan(next_float_up(std::nanf(""))));
  EXPECT_TRUE(std::isnan(next_float_down(std::nanf(""))));
}

TEST(FloatBits, MatchNextafterOnRandomValues) {
  Rng rng(chlorovdb::test::test_seed(5), 0);
  for (int i = 0; i < 100000; ++i) {
    // Random bit patterns: every exponent, both signs, denormals included.
    const uint32_t bits = uint32_t(rng.uniform() * 16777216.f) << 8 | uint32_t(rng.uniform() * 256.f);
    const float v = std::bit_cast<float>(bits);
    if (std::isnan(v)) continue;
    expect_same(next_float_up(v), std::nextafter(v, kInf));
    expect_same(next_float_down(v), std::nextafter(v, -kInf));
  }
}
