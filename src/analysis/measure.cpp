#include "analysis/measure.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "integrator/render.h"

namespace chlorovdb {

namespace {

// Inverse of the standard normal CDF (Acklam's rational approximation, relative error < 1.2e-9).
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02, 1.383577518672690e+02,
                             -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01,
                             -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00, -2.549732539343734e+00,
                             4.374664141464968e+00, 2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - 0.02425) return -normal_quantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

Interval interval(const std::vector<double>& batch_means, double t) {
  const double k = double(batch_means.size());
  double sum = 0, sum2 = 0;
  for (double v : batch_means) sum += v;
  const double mean = sum / k;
  for (double v : batch_means) sum2 += (v - mean) * (v - mean);
  return {mean, t * std::sqrt(sum2 / (k - 1) / k)};
}

}  // namespace

double student_t_quantile(double confidence, int dof) {
  const double z = normal_quantile(0.5 + 0.5 * confidence), n = dof;
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n);
}

RegionMeasurement measure_region(const Scene& scene, const PixelWindow& region, const MeasureOptions& o) {
  if (o.batches < 2 || o.bands < 1 || !(o.confidence > 0 && o.confidence < 1) || region.empty())
    throw std::invalid_argument(fmt::format("measure_region: needs >= 2 batches ({}), >= 1 band ({}), confidence in (0, 1) ({}) "
                                            "and a non-empty region", o.batches, o.bands, o.confidence));
  const int per_batch = (std::max(o.spp, o.batches) + o.batches - 1) / o.batches;
  RegionMeasurement m;
  m.region = region;
  m.batches = o.batches;
  m.spp = per_batch * o.batches;
  m.confidence = o.confidence;
  m.layers = film_layer_names();
  const size_t L = m.layers.size();
  // batch means: [layer][component][batch] for XYZ and RGB, [band][batch] for the spectrum
  std::vector<std::array<std::vector<double>, 3>> xyz(L), rgb(L);
  std::vector<std::vector<double>> spectral(size_t(o.bands)), radiance(1);
  const double pixels = double(region.width()) * region.height();
  for (int k = 0; k < o.batches; ++k) {
    Film film(region.width(), region.height(), m.layers, scene.settings.color_space);
    film.enable_spectral(kLambdaMin, kLambdaMax, o.bands);
    RenderOptions ro;
    ro.first_sample = k * per_batch;
    ro.spp = per_batch;
    ro.film_x0 = region.x0;
    ro.film_y0 = region.y0;
    ro.threads = o.threads;
    ro.seed = o.seed;
    render(scene, film, ro);
    const Image image = film.to_image(per_batch);
    for (size_t l = 0; l < L; ++l) {
      double sx[3] = {0, 0, 0}, sr[3] = {0, 0, 0};
      const std::vector<double>& raw = film.raw_xyz(int(l));
      for (size_t i = 0; i < raw.size(); ++i) sx[i % 3] += raw[i] / per_batch;
      for (size_t i = 0; i < image.layers[l].pixels.size(); ++i) sr[i % 3] += image.layers[l].pixels[i];
      for (int c = 0; c < 3; ++c) {
        xyz[l][size_t(c)].push_back(sx[c] / pixels);
        rgb[l][size_t(c)].push_back(sr[c] / pixels);
      }
    }
    const ImageLayer* s0 = image.find_layer("S0");
    m.band_width_nm = (double(kLambdaMax) - kLambdaMin) / o.bands;
    double total = 0;
    for (int b = 0; b < o.bands; ++b) {
      double sum = 0;
      for (size_t p = 0; p < size_t(pixels); ++p) sum += s0->pixels[p * size_t(o.bands) + size_t(b)];
      spectral[size_t(b)].push_back(sum / pixels);
      total += sum / pixels * m.band_width_nm;
    }
    radiance[0].push_back(total);
  }
  const double t = student_t_quantile(o.confidence, o.batches - 1);
  for (size_t l = 0; l < L; ++l) {
    m.xyz.push_back({interval(xyz[l][0], t), interval(xyz[l][1], t), interval(xyz[l][2], t)});
    m.rgb.push_back({interval(rgb[l][0], t), interval(rgb[l][1], t), interval(rgb[l][2], t)});
  }
  for (int b = 0; b < o.bands; ++b) {
    m.band_centre_nm.push_back(kLambdaMin + (b + 0.5) * m.band_width_nm);
    m.spectral.push_back(interval(spectral[size_t(b)], t));
  }
  m.radiance = interval(radiance[0], t);
  return m;
}

}  // namespace chlorovdb
