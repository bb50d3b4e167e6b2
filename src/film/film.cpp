#include "film/film.h"

#include "core/memory.h"

#include <fmt/format.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>
#include <cmath>
#include <stdexcept>

#include "spectra/color.h"
#include "spectra/library.h"

namespace chlorovdb {

namespace {

// "S0" channel name of the spectral layout: wavelength with a decimal comma, e.g. "552,5nm".
std::string spectral_channel_name(float lambda_nm) {
  std::string s = fmt::format("{}", lambda_nm);  // shortest round-trip form
  if (s.find('.') == std::string::npos) s += ".0";
  std::replace(s.begin(), s.end(), '.', ',');
  return s + "nm";
}

RGB (*rgb_conversion(ColorSpace c))(const XYZ&) { return c == ColorSpace::sRGB ? xyz_to_linear_srgb : xyz_to_acescg; }

constexpr std::string_view kStderrSuffix = "_stderr";
// EXR layers of the AOVs, in bit order.
constexpr std::string_view kAovLayers[] = {"alpha", "depth", "N", "albedo"};

void put_rgb(ImageLayer& layer, size_t pixel, const RGB& rgb) {
  layer.pixels[pixel * 3 + 0] = float(rgb.r);
  layer.pixels[pixel * 3 + 1] = float(rgb.g);
  layer.pixels[pixel * 3 + 2] = float(rgb.b);
}

}  // namespace

const std::vector<std::string>& aov_names() {
  static const std::vector<std::string> names{"alpha", "depth", "normal", "albedo"};
  return names;
}

std::vector<std::string> aov_list(AovMask mask) {
  std::vector<std::string> out;
  for (size_t b = 0; b < aov_names().size(); ++b)
    if (mask & (1u << b)) out.push_back(aov_names()[b]);
  return out;
}

AovMask aov_mask(const std::vector<std::string>& names, std::string* unknown) {
  AovMask mask = 0;
  for (const std::string& n : names) {
    const auto it = std::find(aov_names().begin(), aov_names().end(), n);
    if (it == aov_names().end()) {
      *unknown = n;
      return 0;
    }
    mask |= 1u << unsigned(it - aov_names().begin());
  }
  return mask;
}

bool is_aov_layer(std::string_view name) {
  return std::find(std::begin(kAovLayers), std::end(kAovLayers), name) != std::end(kAovLayers);
}

std::string stderr_layer_name(std::string_view layer) { return std::string(layer) + std::string(kStderrSuffix); }

bool is_stderr_layer(std::string_view name) {
  return name.size() > kStderrSuffix.size() && name.substr(name.size() - kStderrSuffix.size()) == kStderrSuffix;
}

std::string_view stderr_base_name(std::string_view name) { return name.substr(0, name.size() - kStderrSuffix.size()); }

double standard_error(double mean, double sum2, double n) {
  if (!(n >= 2)) return 0.0;
  return std::sqrt(std::max(0.0, sum2 - n * mean * mean) / (n * (n - 1)));
}

Film::Film(int width, int height, std::vector<std::string> layer_names, ColorSpace color_space)
    : width_(width), height_(height), layer_names_(std::move(layer_names)), color_space_(color_space) {
  if (width <= 0 || height <= 0 || layer_names_.empty())
    throw std::invalid_argument(fmt::format("Film: needs a positive size and at least one layer ({}x{}, {} layers)", width,
                                            height, layer_names_.size()));
  // Render holds a second, per-pass film of the same size: refuse before allocating.
  check_memory(2.0 * width * height * layer_names_.size() * 6 * sizeof(double), "the film's sums", "film",
               "resolution", fmt::format("{}x{}", width, height));
  cie_y_integral();  // load the colour-matching functions now: a missing table fails at setup, not mid-render
  xyz_.assign(layer_names_.size(), std::vector<double>(size_t(width) * size_t(height) * 3, 0.0));
  rgb2_ = xyz_;
}

Film::Film(Film&& o) noexcept
    : width_(o.width_),
      height_(o.height_),
      layer_names_(std::move(o.layer_names_)),
      color_space_(o.color_space_),
      xyz_(std::move(o.xyz_)),
      rgb2_(std::move(o.rgb2_)),
      spectral_min_nm_(o.spectral_min_nm_),
      spectral_max_nm_(o.spectral_max_nm_),
      spectral_bins_(o.spectral_bins_),
      spectral_(std::move(o.spectral_)),
      aovs_(o.aovs_),
      aov_(std::move(o.aov_)),
      spp_(std::move(o.spp_)),
      d65_(std::move(o.d65_)),
      nonfinite_(o.nonfinite_samples()) {}

Film& Film::operator=(Film&& o) noexcept {
  width_ = o.width_;
  height_ = o.height_;
  layer_names_ = std::move(o.layer_names_);
  color_space_ = o.color_space_;
  xyz_ = std::move(o.xyz_);
  rgb2_ = std::move(o.rgb2_);
  spectral_min_nm_ = o.spectral_min_nm_;
  spectral_max_nm_ = o.spectral_max_nm_;
  spectral_bins_ = o.spectral_bins_;
  spectral_ = std::move(o.spectral_);
  aovs_ = o.aovs_;
  aov_ = std::move(o.aov_);
  spp_ = std::move(o.spp_);
  d65_ = std::move(o.d65_);
  nonfinite_.store(o.nonfinite_samples(), std::memory_order_relaxed);
  return *this;
}

void Film::enable_spectral(float lambda_min_nm, float lambda_max_nm, int bins) {
  check_memory(2.0 * width_ * height_ * std::max(bins, 0) * sizeof(double), "the spectral bins", "film",
               "spectral_bins", std::to_string(bins));
  if (!(lambda_max_nm > lambda_min_nm) || !std::isfinite(lambda_min_nm) || !std::isfinite(lambda_max_nm) || bins < 1)
    throw std::invalid_argument(
        fmt::format("Film: spectral bins need lambda_min < lambda_max and bins >= 1 ({}, {}, {})", lambda_min_nm, lambda_max_nm, bins));
  spectral_min_nm_ = lambda_min_nm;
  spectral_max_nm_ = lambda_max_nm;
  spectral_bins_ = bins;
  spectral_.assign(size_t(width_) * size_t(height_) * size_t(bins), 0.0);
}

void Film::enable_aovs(AovMask mask) {
  aovs_ = mask;
  if (!mask) {
    aov_.clear();
    return;
  }
  check_memory(2.0 * width_ * height_ * kAovSums * sizeof(double), "the AOV sums", "film", "aovs",
               fmt::format("{}", fmt::join(aov_list(mask), ",")));
  aov_.assign(size_t(width_) * size_t(height_) * kAovSums, 0.0);
  const Spectrum d65 = named_spectrum("D65");
  d65_ = d65.scaled(1.f / luminance(d65));
}

void Film::enable_sample_counts() { spp_.assign(size_t(width_) * size_t(height_), 0.0); }

Film Film::empty_like() const {
  Film f(width_, height_, layer_names_, color_space_);
  if (spectral_bins_ > 0) f.enable_spectral(spectral_min_nm_, spectral_max_nm_, spectral_bins_);
  f.enable_aovs(aovs_);
  if (has_sample_counts()) f.enable_sample_counts();
  return f;
}

void Film::add_sample(int x, int y, int layer, const SampledSpectrum& L, const SampledWavelengths& lambda) {
  assert(x >= 0 && x < width_ && y >= 0 && y < height_ && layer >= 0 && layer < int(xyz_.size()));
  add_layer_sample(size_t(y) * size_t(width_) + size_t(x), layer, L, lambda, xyz_lane_weights(lambda));
}

void Film::add_sample(int x, int y, std::span<const SampledSpectrum> layers, const SampledWavelengths& lambda,
                      const AovSample* aov) {
  assert(x >= 0 && x < width_ && y >= 0 && y < height_ && layers.size() == xyz_.size() && (aov || !aovs_));
  const XyzLaneWeights w = xyz_lane_weights(lambda);
  const size_t pixel = size_t(y) * size_t(width_) + size_t(x);
  for (size_t l = 0; l < layers.size(); ++l)
    if (!layers[l].is_black() || layers[l].has_nonfinite()) add_layer_sample(pixel, int(l), layers[l], lambda, w);
  if (!aovs_ || !aov) return;
  // Y of (1 - T), not 1 - Y of T: the hero-wavelength weights sum to 1 only on average, and this way a ray
  // through vacuum has alpha 0 exactly (the estimator is unbiased either way).
  const double alpha = aov->surface ? 1.0 : to_xyz(SampledSpectrum(1.f) - aov->transmittance, w).y;
  const RGB albedo = rgb_conversion(color_space_)(to_xyz(aov->albedo * d65_.sample(lambda), w));
  const double v[kAovSums] = {alpha,           aov->surface ? aov->depth : 0.0, aov->surface ? 1.0 : 0.0,
                              aov->normal.x,   aov->normal.y,                   aov->normal.z,
                              albedo.r,        albedo.g,                        albedo.b};
  for (double e : v)
    if (!std::isfinite(e)) {
      nonfinite_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
  double* sum = &aov_[pixel * kAovSums];
  for (size_t i = 0; i < kAovSums; ++i) sum[i] += v[i];
}

void Film::add_layer_sample(size_t pixel, int layer, const SampledSpectrum& L, const SampledWavelengths& lambda,
                            const XyzLaneWeights& w) {
  const XYZ xyz = to_xyz(L, w);
  if (L.has_nonfinite() || !std::isfinite(xyz.x) || !std::isfinite(xyz.y) || !std::isfinite(xyz.z)) {
    nonfinite_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  double* sum = &xyz_[size_t(layer)][pixel * 3];
  sum[0] += xyz.x;
  sum[1] += xyz.y;
  sum[2] += xyz.z;
  const RGB rgb = rgb_conversion(color_space_)(xyz);
  double* sum2 = &rgb2_[size_t(layer)][pixel * 3];
  sum2[0] += rgb.r * rgb.r;
  sum2[1] += rgb.g * rgb.g;
  sum2[2] += rgb.b * rgb.b;

  if (layer != 0 || spectral_bins_ == 0) return;
  const float bins_per_nm = float(spectral_bins_) / (spectral_max_nm_ - spectral_min_nm_);
  double* bins = &spectral_[pixel * size_t(spectral_bins_)];
  for (int i = 0; i < lambda.count(); ++i) {
    if (lambda.pdf(i) == 0.f || !(lambda[i] >= spectral_min_nm_ && lambda[i] < spectral_max_nm_)) continue;
    const int b = std::min(int((lambda[i] - spectral_min_nm_) * bins_per_nm), spectral_bins_ - 1);
    bins[b] += double(L[i]) / (double(lambda.pdf(i)) * lambda.count());
  }
}

RGB Film::pixel_mean(int layer, size_t pixel, double n) const {
  const double* s = &xyz_[size_t(layer)][pixel * 3];
  n = pixel_samples(pixel, n);
  const double inv_n = n > 0 ? 1.0 / n : 0.0;  // a counted pixel with no samples is black
  return rgb_conversion(color_space_)({s[0] * inv_n, s[1] * inv_n, s[2] * inv_n});
}

RGB Film::pixel_standard_error(int layer, size_t pixel, double n) const {
  const RGB mean = pixel_mean(layer, pixel, n);  // in double: standard_error's difference cancels
  const double* s2 = &rgb2_[size_t(layer)][pixel * 3];
  n = pixel_samples(pixel, n);
  return {standard_error(mean.r, s2[0], n), standard_error(mean.g, s2[1], n), standard_error(mean.b, s2[2], n)};
}

Image Film::to_image(double samples_per_pixel) const {
  if (!(samples_per_pixel > 0)) throw std::invalid_argument(fmt::format("Film::to_image: samples_per_pixel = {}", samples_per_pixel));
  const size_t pixel_count = size_t(width_) * size_t(height_);
  // 1 / the samples of pixel p (0 for a counted pixel without any).
  const auto inv_spp = [&](size_t p) {
    const double n = pixel_samples(p, samples_per_pixel);
    return n > 0 ? 1.0 / n : 0.0;
  };

  Image image;
  image.width = width_;
  image.height = height_;
  image.chromaticities = color_space_ == ColorSpace::sRGB ? kSrgbChromaticities : kAcesCgChromaticities;
  for (size_t l = 0; l < xyz_.size(); ++l) {
    ImageLayer layer{layer_names_[l], {"R", "G", "B"}, std::vector<float>(pixel_count * 3)};
    for (size_t p = 0; p < pixel_count; ++p) put_rgb(layer, p, pixel_mean(int(l), p, samples_per_pixel));
    image.layers.push_back(std::move(layer));
  }
  if (spectral_bins_ > 0) {
    const double width_nm = (double(spectral_max_nm_) - spectral_min_nm_) / spectral_bins_;
    ImageLayer layer{"S0", {}, std::vector<float>(spectral_.size())};
    for (int b = 0; b < spectral_bins_; ++b)
      layer.channels.push_back(spectral_channel_name(float(spectral_min_nm_ + (b + 0.5) * width_nm)));
    for (size_t i = 0; i < spectral_.size(); ++i) layer.pixels[i] = float(spectral_[i] * inv_spp(i / size_t(spectral_bins_)) / width_nm);
    image.layers.push_back(std::move(layer));
    image.metadata.set("spectral_bin_width_nm", width_nm);
  }
  for (size_t l = 0; l < xyz_.size(); ++l) {
    ImageLayer layer{stderr_layer_name(layer_names_[l]), {"R", "G", "B"}, std::vector<float>(pixel_count * 3)};
    for (size_t p = 0; p < pixel_count; ++p) put_rgb(layer, p, pixel_standard_error(int(l), p, samples_per_pixel));
    image.layers.push_back(std::move(layer));
  }
  const auto aov_layer = [&](AovBit bit, std::vector<std::string> channels, auto&& value) {
    if (!(aovs_ & bit)) return;
    ImageLayer layer{std::string(kAovLayers[std::countr_zero(unsigned(bit))]), std::move(channels), {}};
    layer.pixels.resize(pixel_count * layer.channels.size());
    for (size_t p = 0; p < pixel_count; ++p)
      for (size_t c = 0; c < layer.channels.size(); ++c)
        layer.pixels[p * layer.channels.size() + c] = float(value(&aov_[p * kAovSums], c, inv_spp(p)));
    image.layers.push_back(std::move(layer));
  };
  aov_layer(kAovAlpha, {"A"}, [&](const double* a, size_t, double inv_n) { return a[0] * inv_n; });
  aov_layer(kAovDepth, {"Z", "coverage"}, [&](const double* a, size_t c, double inv_n) {
    return c == 0 ? (a[2] > 0 ? a[1] / a[2] : std::numeric_limits<double>::infinity()) : a[2] * inv_n;
  });
  aov_layer(kAovNormal, {"X", "Y", "Z"}, [&](const double* a, size_t c, double inv_n) { return a[3 + c] * inv_n; });
  aov_layer(kAovAlbedo, {"R", "G", "B"}, [&](const double* a, size_t c, double inv_n) { return a[6 + c] * inv_n; });
  double mean_spp = samples_per_pixel;
  if (has_sample_counts()) {
    ImageLayer layer{"spp", {"N"}, std::vector<float>(pixel_count)};
    double total = 0;
    for (size_t p = 0; p < pixel_count; ++p) layer.pixels[p] = float(spp_[p]), total += spp_[p];
    image.layers.push_back(std::move(layer));
    mean_spp = total / double(pixel_count);
    image.metadata.set("adaptive", 1);
  }
  if (aovs_) image.metadata.set("aovs", fmt::format("{}", fmt::join(aov_list(aovs_), ",")));
  image.metadata.set("color_space", color_space_ == ColorSpace::sRGB ? std::string("linear sRGB (D65)")
                                                                      : std::string("ACEScg (AP1, Bradford-adapted from D65)"));
  image.metadata.set("samples_per_pixel", mean_spp);
  image.metadata.set("nonfinite_samples", double(nonfinite_samples()));  // double: counts can pass 2^31
  return image;
}

void Film::merge(const Film& other) {
  if (other.width_ != width_ || other.height_ != height_ || other.layer_names_ != layer_names_ ||
      other.spectral_bins_ != spectral_bins_ || other.spectral_min_nm_ != spectral_min_nm_ || other.spectral_max_nm_ != spectral_max_nm_ ||
      other.aovs_ != aovs_ || other.spp_.size() != spp_.size())
    throw std::invalid_argument(fmt::format("Film::merge: films differ ({}x{}, {} layers, {} bins vs {}x{}, {} layers, {} bins)", width_,
                                            height_, layer_names_.size(), spectral_bins_, other.width_, other.height_,
                                            other.layer_names_.size(), other.spectral_bins_));
  for (size_t l = 0; l < xyz_.size(); ++l)
    for (size_t i = 0; i < xyz_[l].size(); ++i) {
      xyz_[l][i] += other.xyz_[l][i];
      rgb2_[l][i] += other.rgb2_[l][i];
    }
  for (size_t i = 0; i < spectral_.size(); ++i) spectral_[i] += other.spectral_[i];
  for (size_t i = 0; i < aov_.size(); ++i) aov_[i] += other.aov_[i];
  for (size_t i = 0; i < spp_.size(); ++i) spp_[i] += other.spp_[i];
  nonfinite_.fetch_add(other.nonfinite_samples(), std::memory_order_relaxed);
}

}  // namespace chlorovdb
