#pragma once
// Power-law fits y = a x^k by least squares on (log x, log y): the convergence
// rate of an estimator (k = -1/2 for Monte Carlo) and the cost growth of a
// tracker against optical depth or grid size.
#include <span>
#include <vector>

namespace chlorovdb {

struct PowerFit {
  double exponent = 0;     // k
  double coefficient = 0;  // a
  double r2 = 0;           // coefficient of determination in log space
  int points = 0;          // points used (x > 0 and y > 0)
};

// Points with a non-positive or non-finite x or y are ignored, and so are those
// with x < x_min (the asymptotic rate: an estimator whose rare paths are not yet
// sampled at small x converges faster there than its rate, then slower); fewer
// than two usable points (or all x equal) give points < 2 and exponent 0.
PowerFit fit_power_law(std::span<const double> x, std::span<const double> y, double x_min = 0);

// A quantity measured on independent runs (seeds): its mean and the standard
// error of that mean (the runs' sample spread / sqrt(runs); 0 below two runs).
struct MeanOverRuns {
  double mean = 0, standard_error = 0;
  int runs = 0;
};
MeanOverRuns mean_over_runs(std::span<const double> values);

// A convergence rate measured on independent runs: mean_over_runs of the runs'
// fitted exponents, so a rate is reported with the uncertainty that one run's
// fit cannot give. Fits with fewer than two points are skipped.
MeanOverRuns mean_exponent(std::span<const PowerFit> fits);

}  // namespace chlorovdb
