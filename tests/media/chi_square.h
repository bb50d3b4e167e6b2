#pragma once
// Pearson chi-square goodness of fit for the sampling tests.
#include <cmath>
#include <vector>

namespace chlorovdb::test {

// Chi-square statistic of observed counts against expected counts, pooling
// neighbouring bins until each pooled bin expects at least 5 (the test's
// validity condition). Returns the statistic; *dof receives pooled bins - 1.
inline double chi_square(const std::vector<double>& observed, const std::vector<double>& expected, int* dof) {
  double chi2 = 0, o = 0, e = 0;
  int bins = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    o += observed[i];
    e += expected[i];
    if (e >= 5.0 || i + 1 == observed.size()) {
      chi2 += (o - e) * (o - e) / e;
      ++bins;
      o = e = 0;
    }
  }
  *dof = bins - 1;
  return chi2;
}

// Upper quantile of the chi-square distribution with `dof` degrees of freedom
// for the normal quantile z (Wilson-Hilferty approximation; z = 3.72 is p = 1e-4).
inline double chi_square_quantile(int dof, double z) {
  const double k = dof, a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

}  // namespace chlorovdb::test
