#include "spectra/spectrum.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace chlorovdb {

namespace {

// SI constants (exact since the 2019 redefinition) and Wien's displacement constant.
constexpr double kPlanck = 6.62607015e-34;      // J s
constexpr double kSpeedOfLight = 299792458.0;   // m/s
constexpr double kBoltzmann = 1.380649e-23;     // J/K
constexpr double kWienB = 2.897771955e-3;       // m K

// Planck's law, spectral radiance per metre of wavelength (W sr^-1 m^-3).
double planck(double lambda_nm, double temperature_K) {
  if (lambda_nm <= 0.0) return 0.0;
  const double lambda_m = lambda_nm * 1e-9;
  const double c1 = 2.0 * kPlanck * kSpeedOfLight * kSpeedOfLight;
  const double c2 = kPlanck * kSpeedOfLight / kBoltzmann;
  return c1 / (std::pow(lambda_m, 5) * std::expm1(c2 / (lambda_m * temperature_K)));
}

// Unscaled evaluation of each representation.
float evaluate(const Spectrum::Constant& c, float) { return c.value; }

float evaluate(const Spectrum::Tabulated& t, float lambda_nm) {
  const auto at = t.locate(lambda_nm);
  if (!at) return 0.f;
  // (1-x)a + xb returns the table value exactly at both ends of the segment.
  return (1.f - at->x) * t.value[at->i] + at->x * t.value[at->i + 1];
}

float evaluate(const Spectrum::Blackbody& b, float lambda_nm) {
  return float(planck(lambda_nm, b.temperature_K) * b.normalisation);
}

float evaluate(const Spectrum::Gaussian& g, float lambda_nm) {
  const float z = (lambda_nm - g.mean_nm) / g.sigma_nm;
  return std::exp(-0.5f * z * z);
}

// Exact integral of the piecewise-linear table over [a, b] (a <= b).
double integrate(const Spectrum::Tabulated& t, double a, double b) {
  a = std::max<double>(a, t.lambda.front());
  b = std::min<double>(b, t.lambda.back());
  double sum = 0.0;
  for (size_t i = 0; i + 1 < t.lambda.size(); ++i) {
    const double x0 = t.lambda[i], x1 = t.lambda[i + 1];
    const double lo = std::max(a, x0), hi = std::min(b, x1);
    if (lo >= hi) continue;
    const double slope = (double(t.value[i + 1]) - t.value[i]) / (x1 - x0);
    const double f_lo = t.value[i] + slope * (lo - x0), f_hi = t.value[i] + slope * (hi - x0);
    sum += 0.5 * (f_lo + f_hi) * (hi - lo);
  }
  return sum;
}

// Composite Simpson with steps of at most 1 nm: Planck's curve is smooth on that
// scale, so the relative error is far below float precision.
double integrate(const Spectrum::Blackbody& bb, double a, double b) {
  const int n = 2 * std::max(8, int(std::ceil(0.5 * (b - a))));
  const double h = (b - a) / n;
  double sum = planck(a, bb.temperature_K) + planck(b, bb.temperature_K);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * planck(a + i * h, bb.temperature_K);
  return sum * h / 3.0 * bb.normalisation;
}

double integrate(const Spectrum::Gaussian& g, double a, double b) {
  const double s = g.sigma_nm * std::sqrt(2.0);
  return 0.5 * std::sqrt(2.0 * std::numbers::pi) * g.sigma_nm * (std::erf((b - g.mean_nm) / s) - std::erf((a - g.mean_nm) / s));
}

double integrate(const Spectrum::Constant& c, double a, double b) { return double(c.value) * (b - a); }

}  // namespace

// The guess (the cell, or the guide's segment for it) is corrected by walking, so
// float rounding never picks the wrong segment: i is the last segment starting at or
// below lambda_nm, as a binary search would find.
std::optional<Spectrum::Tabulated::Position> Spectrum::Tabulated::locate(float lambda_nm) const {
  // The negated test also sends NaN to nothing.
  if (!(lambda_nm >= lambda.front() && lambda_nm <= lambda.back())) return std::nullopt;
  const size_t last = lambda.size() - 2;
  const size_t cell = size_t((lambda_nm - lambda[0]) * inv_cell);
  size_t i = guide.empty() ? std::min(cell, last) : guide[std::min(cell, guide.size() - 1)];
  while (i > 0 && lambda_nm < lambda[i]) --i;
  while (i < last && lambda_nm >= lambda[i + 1]) ++i;
  return Position{i, (lambda_nm - lambda[i]) / (lambda[i + 1] - lambda[i])};
}

Spectrum Spectrum::constant(float value) {
  Spectrum s;
  s.rep_ = Constant{value};
  s.source_ = fmt::format("constant {}", value);
  return s;
}

Spectrum Spectrum::tabulated(std::vector<float> lambda, std::vector<float> value, std::string source) {
  if (lambda.size() != value.size())
    throw std::invalid_argument(fmt::format("tabulated spectrum: {} wavelengths but {} values", lambda.size(), value.size()));
  if (lambda.size() < 2)
    throw std::invalid_argument(fmt::format("tabulated spectrum: needs at least 2 samples, got {}", lambda.size()));
  for (size_t i = 0; i < lambda.size(); ++i) {
    if (!std::isfinite(lambda[i]) || !std::isfinite(value[i]))
      throw std::invalid_argument(fmt::format("tabulated spectrum: sample {} ({} nm, {}) is not finite", i, lambda[i], value[i]));
    // No spectral quantity is this large, and integrals over a few hundred nm would overflow float.
    if (std::fabs(value[i]) > kMaxTabulatedValue)
      throw std::invalid_argument(fmt::format("tabulated spectrum: sample {} ({} nm, {}) is beyond ±{:g}, where its integral "
                                              "would overflow", i, lambda[i], value[i], kMaxTabulatedValue));
    if (i > 0 && !(lambda[i] > lambda[i - 1]))
      throw std::invalid_argument(fmt::format("tabulated spectrum: wavelengths must increase strictly ({} nm after {} nm)",
                                              lambda[i], lambda[i - 1]));
  }
  // Evenly spaced within 0.1 % of a step: the O(1) index guess is then off by at most one.
  const double step = (double(lambda.back()) - lambda.front()) / double(lambda.size() - 1);
  bool uniform = true;
  for (size_t i = 0; i < lambda.size() && uniform; ++i)
    uniform = std::fabs(lambda[i] - (lambda.front() + double(i) * step)) <= 1e-3 * step;

  Tabulated t;
  t.lambda = std::move(lambda);
  t.value = std::move(value);
  if (uniform) {
    t.inv_cell = float(1.0 / step);
  } else {
    // Irregular tables (chlorophyll_a's 2562 rows 0.18-0.19 nm apart, the water tables)
    // would otherwise take a binary search per lookup, ~4x an evenly spaced one's cost.
    const size_t cells = 2 * (t.lambda.size() - 1);
    const double width = (double(t.lambda.back()) - t.lambda.front()) / double(cells);
    t.inv_cell = float(1.0 / width);
    t.guide.resize(cells);
    size_t i = 0;
    for (size_t k = 0; k < cells; ++k) {
      const double start = t.lambda.front() + double(k) * width;
      while (i + 2 < t.lambda.size() && double(t.lambda[i + 1]) <= start) ++i;
      t.guide[k] = uint32_t(i);
    }
  }
  Spectrum s;
  s.rep_ = std::move(t);
  s.source_ = source.empty() ? std::string("tabulated") : std::move(source);
  return s;
}

Spectrum Spectrum::blackbody(float temperature_K) {
  if (!(temperature_K > 0.f) || !std::isfinite(temperature_K))
    throw std::invalid_argument(fmt::format("blackbody: temperature must be positive, got {} K", temperature_K));
  // Wien's displacement law gives the peak, so the curve is normalised to 1 there.
  const double peak_nm = kWienB / temperature_K * 1e9;
  Spectrum s;
  s.rep_ = Blackbody{temperature_K, float(1.0 / planck(peak_nm, temperature_K))};
  s.source_ = fmt::format("blackbody {} K", temperature_K);
  return s;
}

Spectrum Spectrum::gaussian(float mean_nm, float sigma_nm, float peak) {
  if (!(sigma_nm > 0.f) || !std::isfinite(sigma_nm) || !std::isfinite(mean_nm) || !std::isfinite(peak))
    throw std::invalid_argument(
        fmt::format("gaussian: needs finite mean and peak and sigma > 0 (mean {} nm, sigma {} nm, peak {})", mean_nm, sigma_nm, peak));
  Spectrum s;
  s.rep_ = Gaussian{mean_nm, sigma_nm};
  s.scale_ = peak;
  s.source_ = fmt::format("gaussian mean {} nm sigma {} nm", mean_nm, sigma_nm);
  return s;
}

float Spectrum::operator()(float lambda_nm) const {
  return scale_ * std::visit([lambda_nm](const auto& r) { return evaluate(r, lambda_nm); }, rep_);
}

SampledSpectrum Spectrum::sample(const SampledWavelengths& lambda) const {
  SampledSpectrum out;
  // One dispatch per call, then a plain loop over the carried wavelengths.
  std::visit(
      [&](const auto& r) {
        for (int i = 0; i < lambda.count(); ++i) out[i] = scale_ * evaluate(r, lambda[i]);
      },
      rep_);
  return out;
}

Spectrum Spectrum::scaled(float s) const {
  Spectrum r = *this;
  r.scale_ *= s;
  return r;
}

float Spectrum::max_value() const {
  if (const auto* t = std::get_if<Tabulated>(&rep_)) {
    float m = scale_ * t->value.front();
    for (float v : t->value) m = std::max(m, scale_ * v);
    return m;
  }
  // Constant, blackbody and Gaussian are unimodal: evaluate at the mode clamped into range.
  float mode = kLambdaMinUV;
  if (const auto* b = std::get_if<Blackbody>(&rep_)) mode = float(kWienB / b->temperature_K * 1e9);
  if (const auto* g = std::get_if<Gaussian>(&rep_)) mode = g->mean_nm;
  return (*this)(std::clamp(mode, kLambdaMinUV, kLambdaMax));
}

float Spectrum::support_min() const {
  const auto* t = std::get_if<Tabulated>(&rep_);
  if (!t) return kLambdaMinUV;
  // Leading zero samples contribute nothing: start at the last of them.
  size_t i = 0;
  while (i + 1 < t->value.size() && t->value[i + 1] == 0.f && t->value[i] == 0.f) ++i;
  return t->lambda[i];
}

float Spectrum::support_max() const {
  const auto* t = std::get_if<Tabulated>(&rep_);
  if (!t) return kLambdaMax;
  size_t i = t->value.size() - 1;
  while (i > 0 && t->value[i - 1] == 0.f && t->value[i] == 0.f) --i;
  return t->lambda[i];
}

float Spectrum::integral(float a, float b) const {
  if (b < a) return -integral(b, a);
  return float(scale_ * std::visit([a, b](const auto& r) { return integrate(r, a, b); }, rep_));
}

}  // namespace chlorovdb
