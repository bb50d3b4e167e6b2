#include "analysis/loglog_fit.h"

#include <cmath>

namespace chlorovdb {

PowerFit fit_power_law(std::span<const double> x, std::span<const double> y, double x_min) {
  PowerFit fit;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  int n = 0;
  for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0) || x[i] < x_min || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    syy += ly * ly;
    ++n;
  }
  fit.points = n;
  if (n < 2) return fit;
  const double vxx = sxx - sx * sx / n, vxy = sxy - sx * sy / n, vyy = syy - sy * sy / n;
  if (!(vxx > 0)) {
    fit.points = 1;
    return fit;
  }
  fit.exponent = vxy / vxx;
  fit.coefficient = std::exp((sy - fit.exponent * sx) / n);
  fit.r2 = vyy > 0 ? vxy * vxy / (vxx * vyy) : 1.0;
  return fit;
}

MeanOverRuns mean_over_runs(std::span<const double> values) {
  MeanOverRuns r;
  r.runs = int(values.size());
  if (r.runs == 0) return r;
  for (double v : values) r.mean += v;
  r.mean /= r.runs;
  if (r.runs < 2) return r;
  double s2 = 0;
  for (double v : values) s2 += (v - r.mean) * (v - r.mean);
  r.standard_error = std::sqrt(s2 / (r.runs - 1) / r.runs);
  return r;
}

MeanOverRuns mean_exponent(std::span<const PowerFit> fits) {
  std::vector<double> exponents;
  for (const PowerFit& f : fits)
    if (f.points >= 2) exponents.push_back(f.exponent);
  return mean_over_runs(exponents);
}

}  // namespace chlorovdb
