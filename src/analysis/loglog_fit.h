#pragma once
// Power-law fits y = a x^k by least squares on (log x, log y): the convergence
// rate of an estimator (k = -1/2 for Monte Carlo) and the cost growth of a
// tracker against optical depth or grid size.
#include <span>

namespace chlorovdb {

struct PowerFit {
  double exponent = 0;     // k
  double coefficient = 0;  // a
  double r2 = 0;           // coefficient of determination in log space
  int points = 0;          // points used (x > 0 and y > 0)
};

// Points with a non-positive or non-finite x or y are ignored; fewer than two
// usable points (or all x equal) give points < 2 and exponent 0.
PowerFit fit_power_law(std::span<const double> x, std::span<const double> y);

}  // namespace chlorovdb
