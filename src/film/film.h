#pragma once
// The film: per pixel and per layer, double-precision sums of each camera
// sample's CIE XYZ estimate (spectra/color.h to_xyz); at the end the mean is
// converted to linear sRGB or ACEScg. Layer 0 is the beauty (total radiance);
// further layers hold parts of it (e.g. fluorescence, non-fluorescence).
//
// Optional spectral bins record the beauty layer's spectral radiance: each lane
// adds L_i / (pdf_i · count) to the bin holding λ_i, an unbiased estimate of
// ∫_bin L dλ; divided by the bin width and spp it is the bin-averaged spectral
// radiance (W m⁻² sr⁻¹ nm⁻¹, relative), written as an EXR spectral layer.
//
// Error as an output: per pixel and layer the film also sums the squares of each
// camera sample's RGB (in the output colour space). The pixel filter is a box of
// one pixel, so every camera sample lands in exactly one pixel and the samples of
// a pixel are i.i.d.: one camera sample carrying N hero wavelengths is ONE sample
// of the pixel estimator (its lanes are summed before squaring, never squared
// lane by lane, which would ignore their correlation). The standard error of the
// mean of n samples is then sqrt((Σx² − n·mean²) / (n (n − 1))), written as a
// layer "<layer>_stderr" beside each layer. Moments (not batch means) because
// they add exactly under merge, checkpoint and resume and need no batch size.
//
// Compositing layers (AOVs, opt-in: render.aovs / --aovs): first-hit quantities of
// each camera sample (integrator/aov.h defines them), summed per pixel like the
// radiance, so they are box-filtered means over the pixel's samples and edges
// antialias: "alpha" (A) = 1 − the ȳ-weighted transmittance to the background, 1 on
// a visible surface; "depth" (Z, coverage) = the mean camera-ray distance to the
// first visible surface over the samples that hit one (+inf where none did) and the
// fraction that did; "N" (X, Y, Z) = the world-space shading normal facing the camera
// (0 for samples that hit nothing, so edges shorten it); "albedo" (R, G, B) = the
// denoiser albedo, reflectance under D65 in the output colour space (white = 1).
//
// Per-pixel sample counts (adaptive sampling, film/adaptive.h): when enabled the
// film counts each pixel's camera samples itself, and every mean, standard error
// and AOV is over that pixel's own count instead of the uniform n callers pass;
// to_image then writes them as an "spp" layer (channel "N") with metadata
// adaptive = 1 and samples_per_pixel = their mean.
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec.h"
#include "io/image.h"
#include "spectra/color.h"
#include "spectra/sampled.h"

namespace chlorovdb {

enum class ColorSpace { sRGB, ACEScg };

// Name of the standard-error layer of `layer` ("total" -> "total_stderr").
std::string stderr_layer_name(std::string_view layer);
bool is_stderr_layer(std::string_view name);

// Standard error of a mean of n samples from the mean and the sum of squares
// (0 for n < 2): sqrt(max(0, sum2 - n mean²) / (n (n - 1))).
double standard_error(double mean, double sum2, double n);
// Its inverse: the sum of squares of n samples whose mean has standard error se,
// n (n - 1) se² + n mean², so means stored with their standard errors (EXR parts,
// a resumed reference) combine exactly like raw moments (up to float rounding).
inline double sum_of_squares(double mean, double se, double n) { return n * (n - 1) * se * se + n * mean * mean; }
// The mean layer a standard-error layer belongs to ("total_stderr" -> "total").
std::string_view stderr_base_name(std::string_view stderr_layer);

// Compositing layers, a bit each (render.aovs).
enum AovBit : unsigned { kAovAlpha = 1, kAovDepth = 2, kAovNormal = 4, kAovAlbedo = 8 };
using AovMask = unsigned;
// The scene-file names, in bit order: "alpha", "depth", "normal", "albedo".
const std::vector<std::string>& aov_names();
std::vector<std::string> aov_list(AovMask mask);  // the names of the set bits
// The mask of `names`; the first name that is not an AOV goes to *unknown (mask then 0).
AovMask aov_mask(const std::vector<std::string>& names, std::string* unknown);
// The EXR layers the AOVs write ("alpha", "depth", "N", "albedo"): means, no standard error.
bool is_aov_layer(std::string_view name);

// One camera sample's first-hit quantities (integrator/aov.h fills them).
struct AovSample {
  bool surface = false;                // the camera ray reached a visible surface
  float depth = 0;                     // its distance along the camera ray, metres
  Vec3 normal{0, 0, 0};                // its world-space shading normal, facing the camera
  SampledSpectrum transmittance{1.f};  // to the background, when !surface (alpha = 1 - its Y)
  SampledSpectrum albedo{0.f};         // reflectance of the first non-specular surface
};

class Film {
 public:
  Film(int width, int height, std::vector<std::string> layer_names, ColorSpace color_space);
  Film(Film&& other) noexcept;
  Film& operator=(Film&& other) noexcept;

  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<std::string>& layer_names() const { return layer_names_; }
  ColorSpace color_space() const { return color_space_; }
  float spectral_min_nm() const { return spectral_min_nm_; }
  float spectral_max_nm() const { return spectral_max_nm_; }
  int spectral_bins() const { return spectral_bins_; }

  // Bins of equal width over [lambda_min, lambda_max) nm for the beauty layer.
  void enable_spectral(float lambda_min_nm, float lambda_max_nm, int bins);
  // Sums for the compositing layers in `mask` (all kAovSums per pixel when any is set).
  void enable_aovs(AovMask mask);
  AovMask aovs() const { return aovs_; }
  // Count samples per pixel (add_sample_count); empty_like and merge carry the counts.
  void enable_sample_counts();
  bool has_sample_counts() const { return !spp_.empty(); }
  // `count` more camera samples went to pixel (x, y); thread-safe for distinct pixels.
  void add_sample_count(int x, int y, int count) { spp_[size_t(y) * size_t(width_) + size_t(x)] += count; }
  // The samples of film pixel `pixel`: its own count when counted, else n.
  double pixel_samples(size_t pixel, double n) const { return spp_.empty() ? n : spp_[pixel]; }
  const std::vector<double>& raw_sample_counts() const { return spp_; }
  // A film of the same size, layers, colour space, bins and AOVs, all sums zero.
  Film empty_like() const;

  // Thread-safe for distinct pixels (tiles are disjoint), so pixels need no atomics.
  // A sample with a non-finite value in any lane, or a non-finite estimate, is
  // dropped and counted instead.
  void add_sample(int x, int y, int layer, const SampledSpectrum& L, const SampledWavelengths& lambda);
  // One sample of every layer at once (layers[l] for layer l): the colour-matching
  // functions are looked up once, and black layers cost nothing.
  // `aov` (required when AOVs are enabled) adds the sample's first-hit quantities.
  void add_sample(int x, int y, std::span<const SampledSpectrum> layers, const SampledWavelengths& lambda,
                  const AovSample* aov = nullptr);
  uint64_t nonfinite_samples() const { return nonfinite_.load(std::memory_order_relaxed); }

  // Mean over `samples_per_pixel` samples (each pixel's own count when counted): one RGB layer per layer name (channels
  // R, G, B), then the spectral layer "S0" (channels "<centre>nm", decimal comma)
  // if enabled, then one "<layer>_stderr" RGB layer per layer (standard error of
  // the mean, same units). Metadata: color_space, samples_per_pixel, nonfinite_samples.
  Image to_image(double samples_per_pixel) const;

  // The mean and its standard error of film pixel `pixel` (y·width + x) of a layer
  // over n samples, RGB in the film's colour space (what to_image writes, in double).
  RGB pixel_mean(int layer, size_t pixel, double n) const;
  RGB pixel_standard_error(int layer, size_t pixel, double n) const;

  // Raw sums, for merging renders of the same view: (y·width + x)·3 + {X, Y, Z},
  // and (y·width + x)·bins + bin for the spectral sums.
  const std::vector<double>& raw_xyz(int layer) const { return xyz_[size_t(layer)]; }
  const std::vector<double>& raw_spectral() const { return spectral_; }
  // Sums of squares of each sample's RGB (output colour space): (y·width + x)·3 + {R, G, B}.
  const std::vector<double>& raw_rgb_squares(int layer) const { return rgb2_[size_t(layer)]; }
  // AOV sums, (y·width + x)·kAovSums + {alpha, depth, hits, N.x, N.y, N.z, albedo R, G, B}
  // (depth summed over the samples that hit a surface, `hits` of them); empty without AOVs.
  static constexpr size_t kAovSums = 9;
  const std::vector<double>& raw_aovs() const { return aov_; }
  // Adds another film's sums and non-finite count; throws std::invalid_argument
  // unless size, layers, spectral bins and AOVs agree.
  void merge(const Film& other);

 private:
  void add_layer_sample(size_t pixel, int layer, const SampledSpectrum& L, const SampledWavelengths& lambda,
                        const XyzLaneWeights& w);
  int width_, height_;
  std::vector<std::string> layer_names_;
  ColorSpace color_space_;
  std::vector<std::vector<double>> xyz_;
  std::vector<std::vector<double>> rgb2_;
  float spectral_min_nm_ = 0.f, spectral_max_nm_ = 0.f;
  int spectral_bins_ = 0;
  std::vector<double> spectral_;
  AovMask aovs_ = 0;
  std::vector<double> aov_;
  std::vector<double> spp_;  // per-pixel sample counts (empty: uniform)
  Spectrum d65_;  // the albedo's illuminant, normalised to Y = 1 (set by enable_aovs)
  std::atomic<uint64_t> nonfinite_{0};
};

}  // namespace chlorovdb
