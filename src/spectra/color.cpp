#include "spectra/color.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <variant>

#include "spectra/csv.h"
#include "spectra/library.h"

namespace chlorovdb {

namespace {

// ---- CIE 1931 colour-matching functions ------------------------------------

struct CieCmfs {
  Spectrum x, y, z;
  double y_integral;
  // The three tables side by side (one CSV, one wavelength grid): the film weighs
  // every lane of every sample with them, and three Spectrum calls cost 3x one lookup.
  std::vector<std::array<float, 3>> xyz;
};

// Loaded on first use (thread-safe static); a failed load throws and is retried next call.
const CieCmfs& cmfs() {
  static const CieCmfs c = [] {
    const std::filesystem::path path = spectra_dir() / "cie1931_2deg_xyz.csv";
    CieCmfs r{load_spectrum_csv(path, "x"), load_spectrum_csv(path, "y"), load_spectrum_csv(path, "z"), 0.0};
    // Trapezoids are exact for the piecewise-linear ȳ; summed in double (Spectrum::integral is float).
    const auto& y = std::get<Spectrum::Tabulated>(r.y.representation());
    for (size_t i = 0; i + 1 < y.lambda.size(); ++i)
      r.y_integral += 0.5 * (double(y.value[i]) + y.value[i + 1]) * (double(y.lambda[i + 1]) - y.lambda[i]);
    const auto& x = std::get<Spectrum::Tabulated>(r.x.representation());
    const auto& z = std::get<Spectrum::Tabulated>(r.z.representation());
    for (size_t i = 0; i < y.lambda.size(); ++i)
      r.xyz.push_back({x.value[i], y.value[i], z.value[i]});
    return r;
  }();
  return c;
}

// Simpson's rule on [a, b] for f·cmf, all three components at once.
template <typename F>
XYZ simpson_xyz(F&& f, double a, double b) {
  const double m = 0.5 * (a + b);
  const XYZ ca = cie_cmf(float(a)), cm = cie_cmf(float(m)), cb = cie_cmf(float(b));
  const double fa = f(a), fm = f(m), fb = f(b), w = (b - a) / 6.0;
  return {w * (fa * ca.x + 4 * fm * cm.x + fb * cb.x), w * (fa * ca.y + 4 * fm * cm.y + fb * cb.y),
          w * (fa * ca.z + 4 * fm * cm.z + fb * cb.z)};
}

// ---- 3×3 matrices for the RGB spaces, derived from chromaticities ----------

using Mat3 = std::array<std::array<double, 3>, 3>;

constexpr Mat3 mul(const Mat3& a, const Mat3& b) {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) r[i][j] += a[i][k] * b[k][j];
  return r;
}

constexpr std::array<double, 3> mul(const Mat3& m, const std::array<double, 3>& v) {
  return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
          m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

constexpr Mat3 inverse(const Mat3& m) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double inv_det = 1.0 / (m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02);
  return {{{c00 * inv_det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv_det, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv_det},
           {c01 * inv_det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv_det, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv_det},
           {c02 * inv_det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv_det, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv_det}}};
}

// XYZ of chromaticity (x, y) at luminance Y = 1.
constexpr std::array<double, 3> xyz_from_xy(double x, double y) { return {x / y, 1.0, (1.0 - x - y) / y}; }

// Columns are the primaries' XYZ, scaled so that RGB (1, 1, 1) maps to the white point at Y = 1.
constexpr Mat3 xyz_from_rgb(const Chromaticities& c) {
  const auto r = xyz_from_xy(c.red_x, c.red_y), g = xyz_from_xy(c.green_x, c.green_y), b = xyz_from_xy(c.blue_x, c.blue_y);
  const Mat3 primaries{{{r[0], g[0], b[0]}, {r[1], g[1], b[1]}, {r[2], g[2], b[2]}}};
  const auto s = mul(inverse(primaries), xyz_from_xy(c.white_x, c.white_y));
  Mat3 m{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = primaries[i][j] * s[j];
  return m;
}

// Bradford chromatic adaptation (Lam 1985) from white `from` to white `to`:
// von Kries scaling in the Bradford "cone" space.
constexpr Mat3 kBradford{{{0.8951, 0.2664, -0.1614}, {-0.7502, 1.7135, 0.0367}, {0.0389, -0.0685, 1.0296}}};

constexpr Mat3 bradford_adaptation(double from_x, double from_y, double to_x, double to_y) {
  const auto src = mul(kBradford, xyz_from_xy(from_x, from_y)), dst = mul(kBradford, xyz_from_xy(to_x, to_y));
  const Mat3 scale{{{dst[0] / src[0], 0, 0}, {0, dst[1] / src[1], 0}, {0, 0, dst[2] / src[2]}}};
  return mul(inverse(kBradford), mul(scale, kBradford));
}

constexpr Mat3 kSrgbFromXyz = inverse(xyz_from_rgb(kSrgbChromaticities));
constexpr Mat3 kAcesCgFromXyz =
    mul(inverse(xyz_from_rgb(kAcesCgChromaticities)),
        bradford_adaptation(kSrgbChromaticities.white_x, kSrgbChromaticities.white_y, kAcesCgChromaticities.white_x,
                            kAcesCgChromaticities.white_y));

RGB apply(const Mat3& m, const XYZ& c) {
  const auto v = mul(m, std::array<double, 3>{c.x, c.y, c.z});
  return {v[0], v[1], v[2]};
}

}  // namespace

XYZ cie_cmf(float lambda_nm) {
  const CieCmfs& c = cmfs();
  // What c.x(lambda_nm), c.y(...), c.z(...) return, bit for bit, with one table lookup.
  const auto at = std::get<Spectrum::Tabulated>(c.y.representation()).locate(lambda_nm);
  if (!at) return {0.0, 0.0, 0.0};
  const float f = at->x;
  const std::array<float, 3>&a = c.xyz[at->i], &b = c.xyz[at->i + 1];
  return {((1.f - f) * a[0] + f * b[0]) * c.x.scale(), ((1.f - f) * a[1] + f * b[1]) * c.y.scale(),
          ((1.f - f) * a[2] + f * b[2]) * c.z.scale()};
}

double cie_y_integral() { return cmfs().y_integral; }

XyzLaneWeights xyz_lane_weights(const SampledWavelengths& lambda) {
  XyzLaneWeights w;
  const double norm = 1.0 / (double(lambda.count()) * cie_y_integral());
  for (int i = 0; i < lambda.count(); ++i) {
    if (lambda.pdf(i) == 0.f) continue;
    const XYZ cmf = cie_cmf(lambda[i]);
    const double k = norm / lambda.pdf(i);
    w.x[i] = cmf.x * k;
    w.y[i] = cmf.y * k;
    w.z[i] = cmf.z * k;
  }
  return w;
}

XYZ to_xyz(const SampledSpectrum& L, const XyzLaneWeights& w) {
  XYZ sum;
  for (int i = 0; i < kMaxWavelengths; ++i) {
    sum.x += w.x[i] * L[i];
    sum.y += w.y[i] * L[i];
    sum.z += w.z[i] * L[i];
  }
  return sum;
}

XYZ to_xyz(const SampledSpectrum& L, const SampledWavelengths& lambda) { return to_xyz(L, xyz_lane_weights(lambda)); }

XYZ spectrum_to_xyz(const Spectrum& s) {
  // Knots: the CMF table's samples (1 nm) plus the spectrum's own, where the
  // product of two piecewise-linear functions may kink.
  std::vector<double> knots;
  for (float l : std::get<Spectrum::Tabulated>(cmfs().y.representation()).lambda) knots.push_back(l);
  double max_step = 1e30;  // tabulated/constant: Simpson is exact between knots
  if (const auto* t = std::get_if<Spectrum::Tabulated>(&s.representation())) {
    for (float l : t->lambda)
      if (l > kLambdaMin && l < kLambdaMax) knots.push_back(l);
    std::sort(knots.begin(), knots.end());
    knots.erase(std::unique(knots.begin(), knots.end()), knots.end());
  } else if (const auto* g = std::get_if<Spectrum::Gaussian>(&s.representation())) {
    max_step = g->sigma_nm / 4.0;  // resolve narrow lines
  }
  const auto f = [&s](double lambda) { return double(s(float(lambda))); };
  XYZ sum;
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    const int n = std::max(1, int(std::ceil((knots[k + 1] - knots[k]) / max_step)));
    const double h = (knots[k + 1] - knots[k]) / n;
    for (int j = 0; j < n; ++j) {
      const XYZ part = simpson_xyz(f, knots[k] + j * h, j + 1 == n ? knots[k + 1] : knots[k] + (j + 1) * h);
      sum.x += part.x, sum.y += part.y, sum.z += part.z;
    }
  }
  const double norm = 1.0 / cie_y_integral();
  return {sum.x * norm, sum.y * norm, sum.z * norm};
}

float luminance(const Spectrum& s) { return float(spectrum_to_xyz(s).y); }

RGB xyz_to_linear_srgb(const XYZ& xyz) { return apply(kSrgbFromXyz, xyz); }

RGB xyz_to_acescg(const XYZ& xyz) { return apply(kAcesCgFromXyz, xyz); }

float srgb_encode(float linear) {
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.f / 2.4f) - 0.055f;
}

}  // namespace chlorovdb
