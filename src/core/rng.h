#pragma once
// PCG32 (O'Neill 2014): small, fast, and splittable into independent streams,
// which gives every pixel its own deterministic stream whatever the thread count.
#include <cstdint>

namespace chlorovdb {

// 64-bit mix (MurmurHash3 finaliser) for deriving seeds from pixel coordinates.
constexpr uint64_t mix_bits(uint64_t v) {
  v ^= v >> 33;
  v *= 0xff51afd7ed558ccdULL;
  v ^= v >> 33;
  v *= 0xc4ceb9fe1a85ec53ULL;
  v ^= v >> 33;
  return v;
}

constexpr uint64_t hash_combine(uint64_t a, uint64_t b) { return mix_bits(a ^ (mix_bits(b) + 0x9e3779b97f4a7c15ULL)); }

class Rng {
 public:
  constexpr Rng() { seed(0, 0x853c49e6748fea9bULL); }
  constexpr Rng(uint64_t seq_index, uint64_t offset) { seed(seq_index, offset); }

  constexpr void seed(uint64_t seq_index, uint64_t offset) {
    state_ = 0u;
    inc_ = (seq_index << 1u) | 1u;
    next_u32();
    state_ += offset;
    next_u32();
  }

  constexpr uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 0x5851f42d4c957f2dULL + inc_;
    const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }

  // Uniform in [0, 1): 24 random mantissa bits, never rounds up to 1.
  constexpr float uniform() { return float(next_u32() >> 8) * 0x1p-24f; }

  // Jump the stream ahead by `delta` steps in O(log delta) (Brown 1994).
  constexpr void advance(uint64_t delta) {
    uint64_t cur_mult = 0x5851f42d4c957f2dULL, cur_plus = inc_, acc_mult = 1u, acc_plus = 0u;
    while (delta > 0) {
      if (delta & 1) {
        acc_mult *= cur_mult;
        acc_plus = acc_plus * cur_mult + cur_plus;
      }
      cur_plus = (cur_mult + 1) * cur_plus;
      cur_mult *= cur_mult;
      delta /= 2;
    }
    state_ = acc_mult * state_ + acc_plus;
  }

 private:
  uint64_t state_ = 0, inc_ = 1;
};

}  // namespace chlorovdb
