#include "analysis/loglog_fit.h"

#include <algorithm>
#include <cmath>

namespace chlorovdb {

PowerFit fit_power_law(std::span<const double> x, std::span<const double> y) {
  PowerFit fit;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  int n = 0;
  for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
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

ExponentOverRuns mean_exponent(std::span<const PowerFit> fits) {
  ExponentOverRuns r;
  double sum = 0, sum2 = 0;
  for (const PowerFit& f : fits) {
    if (f.points < 2) continue;
    sum += f.exponent;
    sum2 += f.exponent * f.exponent;
    ++r.runs;
  }
  if (r.runs == 0) return r;
  r.mean = sum / r.runs;
  if (r.runs > 1) r.standard_error = std::sqrt(std::max(0.0, (sum2 - r.runs * r.mean * r.mean) / (r.runs - 1)) / r.runs);
  return r;
}

}  // namespace chlorovdb
