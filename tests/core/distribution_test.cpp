#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Weights with what the renderer's tables have: runs of zero bins (a light spectrum
// outside its band), one bin far above the rest (a mercury line), and a smooth part.
std::vector<float> uneven_weights(int n) {
  Rng rng(test_seed(17), 0);
  std::vector<float> w(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) w[size_t(i)] = (i / 37) % 3 == 1 ? 0.f : rng.uniform() * rng.uniform();
  w[size_t(n / 2)] = 5000.f;
  w[0] = 0.f;
  w[size_t(n) - 1] = 0.f;
  return w;
}

// The bin a binary search over the CDF finds (the first whose upper edge exceeds u),
// then back over zero-probability bins, with the CDF accumulated as the class does.
struct SearchedBin {
  explicit SearchedBin(const std::vector<float>& weights) : w(weights), cdf{0.0} {
    double sum = 0;
    for (const float x : w) sum += x;
    for (const float x : w) cdf.push_back(cdf.back() + x / sum);
    cdf.back() = 1.0;
  }
  int operator()(float u) const {
    int i = std::clamp(int(std::upper_bound(cdf.begin() + 1, cdf.end(), double(u)) - cdf.begin()) - 1, 0,
                       int(w.size()) - 1);
    while (w[size_t(i)] == 0.f && i > 0) --i;
    return i;
  }
  std::vector<float> w;
  std::vector<double> cdf;
};

}  // namespace

// sample() starts from a guide cell and walks: it must land where the binary search
// does for every u, including the CDF's edges and their float neighbours.
TEST(Distribution1D, SampleFindsTheBinABinarySearchFinds) {
  for (const int n : {1, 2, 3, 940, 4096}) {
    const std::vector<float> w = n < 4 ? std::vector<float>(size_t(n), 1.f) : uneven_weights(n);
    const Distribution1D d(w);
    const SearchedBin searched_bin(w);
    std::vector<float> us;
    for (const double edge : searched_bin.cdf)
      for (const float e : {float(edge), std::nextafter(float(edge), 0.f), std::nextafter(float(edge), 1.f)})
        if (e >= 0.f && e < 1.f) us.push_back(e);
    for (int k = 0; k < 20000; ++k) us.push_back(float(k) / 20000.f);
    us.push_back(0x1.fffffep-1f);
    for (const float u : us) {
      float pmf = -1.f, remapped = -1.f;
      const int i = d.sample(u, &pmf, &remapped);
      ASSERT_EQ(i, searched_bin(u)) << "n = " << n << ", u = " << u;
      ASSERT_GT(pmf, 0.f) << "n = " << n << ", u = " << u;
      ASSERT_EQ(pmf, d.pmf(i));
      ASSERT_TRUE(remapped >= 0.f && remapped < 1.f) << remapped;
    }
  }
}

// Frequencies of a sampled index match the weights within 4σ of a multinomial count.
TEST(Distribution1D, IndexFrequenciesFollowTheWeights) {
  const std::vector<float> w = {0.f, 1.f, 0.f, 3.f, 0.5f, 0.f, 2.5f};
  const Distribution1D d(w);
  Rng rng(test_seed(3), 0);
  const int n = 200000;
  std::vector<int> count(w.size(), 0);
  for (int k = 0; k < n; ++k) ++count[size_t(d.sample(rng.uniform()))];
  for (size_t i = 0; i < w.size(); ++i) {
    const double p = w[i] / 7.0;
    EXPECT_NEAR(count[i], n * p, 4.0 * std::sqrt(n * p * (1 - p)) + 1e-9) << i;
  }
}
