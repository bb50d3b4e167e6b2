#pragma once
// Render regression statistics (as Mitsuba 3's scene tests): a scene rendered in
// independent batches gives, per pixel and per 8x8 block, the mean of the
// per-batch means and the variance of that mean estimated from the batches
// themselves (estimator-agnostic, correct under pixel filters and correlated
// pixels). Two such estimates are compared by per-statistic Welch t-tests with a
// Bonferroni/Holm correction: the family is rejected when the smallest p-value
// is below alpha / N (Holm's first step; Holm rejects anything exactly then).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace chlorovdb::regression {

// Per-statistic mean and variance of the mean over `batches` batches.
struct Estimate {
  int width = 0, height = 0;  // image size; statistics: 3 XYZ per pixel, then 3 per block
  int batches = 0, spp_per_batch = 0;
  uint64_t seed = 0;
  std::vector<double> mean, var;  // var = sample variance of the batch means / batches
};

// Accumulates batch images (XYZ per pixel) into an Estimate.
class BatchAccumulator {
 public:
  static constexpr int kBlock = 8;
  BatchAccumulator(int width, int height) : width_(width), height_(height) {}
  // xyz: 3 values per pixel, row-major: one batch's per-pixel means.
  void add_batch(const std::vector<double>& xyz) {
    const std::vector<double> s = statistics(xyz);
    if (sum_.empty()) sum_.assign(s.size(), 0.0), sum2_.assign(s.size(), 0.0);
    for (size_t i = 0; i < s.size(); ++i) sum_[i] += s[i], sum2_[i] += s[i] * s[i];
    ++batches_;
  }
  Estimate estimate() const {
    Estimate e;
    e.width = width_, e.height = height_, e.batches = batches_, e.spp_per_batch = 1;
    e.mean.resize(sum_.size()), e.var.resize(sum_.size());
    const double n = batches_;
    for (size_t i = 0; i < sum_.size(); ++i) {
      e.mean[i] = sum_[i] / n;
      const double s2 = std::max(0.0, (sum2_[i] - n * e.mean[i] * e.mean[i]) / (n - 1));
      e.var[i] = s2 / n;
    }
    return e;
  }
  // Pixel values then the means of kBlock x kBlock blocks (partial blocks at the edges).
  std::vector<double> statistics(const std::vector<double>& xyz) const {
    std::vector<double> s(xyz);
    const int bw = (width_ + kBlock - 1) / kBlock, bh = (height_ + kBlock - 1) / kBlock;
    for (int by = 0; by < bh; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        double acc[3] = {0, 0, 0};
        int n = 0;
        for (int y = by * kBlock; y < std::min(height_, (by + 1) * kBlock); ++y)
          for (int x = bx * kBlock; x < std::min(width_, (bx + 1) * kBlock); ++x, ++n)
            for (int c = 0; c < 3; ++c) acc[c] += xyz[3 * (size_t(y) * width_ + x) + c];
        for (int c = 0; c < 3; ++c) s.push_back(acc[c] / n);
      }
    return s;
  }

 private:
  int width_, height_, batches_ = 0;
  std::vector<double> sum_, sum2_;
};

// Regularised incomplete beta I_x(a, b) (continued fraction, Numerical Recipes §6.4).
inline double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  auto cf = [](double a, double b, double x) {
    const double tiny = 1e-300;
    double c = 1, d = 1 - (a + b) * x / (a + 1);
    d = 1 / (std::abs(d) < tiny ? tiny : d);
    double h = d;
    for (int m = 1; m < 300; ++m) {
      const double m2 = 2.0 * m;
      double aa = m * (b - m) * x / ((a + m2 - 1) * (a + m2));
      d = 1 + aa * d, c = 1 + aa / c;
      d = 1 / (std::abs(d) < tiny ? tiny : d), c = std::abs(c) < tiny ? tiny : c;
      h *= d * c;
      aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1));
      d = 1 + aa * d, c = 1 + aa / c;
      d = 1 / (std::abs(d) < tiny ? tiny : d), c = std::abs(c) < tiny ? tiny : c;
      const double del = d * c;
      h *= del;
      if (std::abs(del - 1) < 1e-14) break;
    }
    return h;
  };
  const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x));
  return x < (a + 1) / (a + b + 2) ? front * cf(a, b, x) / a : 1 - front * cf(b, a, 1 - x) / b;
}

// Two-sided p-value of Student's t with `df` degrees of freedom.
inline double student_t_p(double t, double df) { return incomplete_beta(df / 2, 0.5, df / (df + t * t)); }

struct Comparison {
  size_t tests = 0;
  double min_p = 1;     // smallest p-value
  size_t worst = 0;     // its statistic
  double worst_t = 0;
  size_t rejected = 0;  // Holm rejections at alpha
  bool failed() const { return rejected > 0; }
};

// Welch t-test of every statistic of the test estimate `a` against the reference `b`,
// Holm-corrected at `alpha`. Heavy tails (rare huge samples: liquid in glass under
// UV) make a short render's own batch variance far too small whenever it misses
// the rare samples, so the test's variance is at least what the reference's
// per-sample variance predicts for the test's sample count (under the null both
// draw the same samples): a render that misses a rare firefly is not a regression.
// A statistic with zero variance in both (a black pixel) must agree to rounding.
inline Comparison compare(const Estimate& a, const Estimate& b, double alpha) {
  Comparison r;
  std::vector<double> p(a.mean.size(), 1.0);
  r.tests = p.size();
  const double samples_ratio = double(b.batches) * std::max(1, b.spp_per_batch) /
                               (double(a.batches) * std::max(1, a.spp_per_batch));
  for (size_t i = 0; i < p.size(); ++i) {
    const double predicted = b.var[i] * samples_ratio;
    const bool own = a.var[i] >= predicted;
    const double va = own ? a.var[i] : predicted;
    const int batches_a = own ? a.batches : b.batches;
    const double d = a.mean[i] - b.mean[i], v = va + b.var[i];
    if (!(v > 0)) {
      p[i] = std::abs(d) <= 1e-6 * std::max(std::abs(a.mean[i]), std::abs(b.mean[i])) ? 1.0 : 0.0;
    } else {
      // Welch-Satterthwaite degrees of freedom.
      const double df = v * v / (va * va / std::max(1, batches_a - 1) + b.var[i] * b.var[i] / std::max(1, b.batches - 1));
      p[i] = student_t_p(d / std::sqrt(v), std::max(1.0, df));
    }
    if (p[i] < r.min_p) r.min_p = p[i], r.worst = i, r.worst_t = v > 0 ? d / std::sqrt(v) : INFINITY;
  }
  std::vector<double> sorted(p);
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 0; k < sorted.size() && sorted[k] < alpha / double(sorted.size() - k); ++k) ++r.rejected;
  return r;
}

}  // namespace chlorovdb::regression
