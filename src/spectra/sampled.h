#pragma once
// The three spectral types are kept apart (as in pbrt-v4):
//   Spectrum           a function of wavelength (spectrum.h)
//   SampledWavelengths the wavelengths one camera path carries, with their pdf
//   SampledSpectrum    the values of some quantity at those wavelengths
// A path carries `count` wavelengths (runtime, <= kMaxWavelengths). Lanes past
// `count` hold zero so whole-array arithmetic stays valid and vectorisable.
#include <algorithm>
#include <array>
#include <cmath>

namespace chlorovdb {

inline constexpr int kMaxWavelengths = 16;
inline constexpr float kLambdaMin = 360.f;  // camera (visible) range, nm
inline constexpr float kLambdaMax = 830.f;
inline constexpr float kLambdaMinUV = 250.f;  // light / excitation spectra reach into UVB

class SampledSpectrum {
 public:
  SampledSpectrum() { v_.fill(0.f); }
  explicit SampledSpectrum(float c) { v_.fill(c); }

  float operator[](int i) const { return v_[i]; }
  float& operator[](int i) { return v_[i]; }

#define CHLOROVDB_LANEWISE(op)                                                      \
  SampledSpectrum& operator op##=(const SampledSpectrum& o) {                       \
    for (int i = 0; i < kMaxWavelengths; ++i) v_[i] op## = o.v_[i];                 \
    return *this;                                                                   \
  }                                                                                 \
  SampledSpectrum operator op(const SampledSpectrum& o) const {                     \
    SampledSpectrum r = *this;                                                      \
    return r op## = o;                                                              \
  }
  CHLOROVDB_LANEWISE(+)
  CHLOROVDB_LANEWISE(-)
  CHLOROVDB_LANEWISE(*)
#undef CHLOROVDB_LANEWISE

  SampledSpectrum& operator*=(float s) {
    for (float& x : v_) x *= s;
    return *this;
  }
  SampledSpectrum operator*(float s) const {
    SampledSpectrum r = *this;
    return r *= s;
  }
  friend SampledSpectrum operator*(float s, const SampledSpectrum& a) { return a * s; }
  SampledSpectrum& operator/=(float s) { return *this *= 1.f / s; }
  SampledSpectrum operator/(float s) const { return *this * (1.f / s); }

  // Lane-wise a / b with 0 where b == 0 (inactive lanes, terminated wavelengths).
  friend SampledSpectrum safe_div(const SampledSpectrum& a, const SampledSpectrum& b) {
    SampledSpectrum r;
    for (int i = 0; i < kMaxWavelengths; ++i) r.v_[i] = b.v_[i] != 0.f ? a.v_[i] / b.v_[i] : 0.f;
    return r;
  }
  friend SampledSpectrum clamp_zero(const SampledSpectrum& a) {
    SampledSpectrum r;
    for (int i = 0; i < kMaxWavelengths; ++i) r.v_[i] = std::max(0.f, a.v_[i]);
    return r;
  }
  friend SampledSpectrum exp_neg(const SampledSpectrum& a) {  // e^{-a}
    SampledSpectrum r;
    for (int i = 0; i < kMaxWavelengths; ++i) r.v_[i] = std::exp(-a.v_[i]);
    return r;
  }

  bool is_black() const {
    for (float x : v_)
      if (x != 0.f) return false;
    return true;
  }
  bool has_nonfinite() const {
    for (float x : v_)
      if (!std::isfinite(x)) return true;
    return false;
  }
  float max_value() const { return *std::max_element(v_.begin(), v_.end()); }
  // Mean over the first `count` lanes (the ones a path actually carries).
  float average(int count) const {
    float s = 0;
    for (int i = 0; i < count; ++i) s += v_[i];
    return s / float(count);
  }

 private:
  std::array<float, kMaxWavelengths> v_;
};

class SampledWavelengths {
 public:
  // Stratified hero-wavelength sampling over [kLambdaMin, kLambdaMax] with the
  // visible-importance pdf (spectra/wavelength_sampling.cpp).
  static SampledWavelengths sample_visible(float u, int count);
  // Stratified uniform sampling over [lambda_min, lambda_max] (tests, narrow ranges).
  static SampledWavelengths sample_uniform(float u, int count, float lambda_min, float lambda_max);
  // One wavelength with pdf 1 (excitation rays, analytic tests).
  static SampledWavelengths single(float lambda_nm) {
    SampledWavelengths w;
    w.count_ = 1;
    w.lambda_[0] = lambda_nm;
    w.pdf_[0] = 1.f;
    return w;
  }
  // Explicit wavelengths and pdfs (tests, spectral references).
  static SampledWavelengths from_values(const float* lambda_nm, const float* pdf, int count) {
    SampledWavelengths w;
    w.count_ = count;
    for (int i = 0; i < count; ++i) w.lambda_[i] = lambda_nm[i], w.pdf_[i] = pdf[i];
    return w;
  }

  int count() const { return count_; }
  float operator[](int i) const { return lambda_[i]; }
  float pdf(int i) const { return pdf_[i]; }
  const SampledSpectrum& pdf() const { return pdf_; }

  // After a wavelength-dependent event (dispersion) only the hero wavelength
  // survives: the others get pdf 0 and the hero's pdf is divided by `count`, so
  // the film's average over `count` lanes stays unbiased.
  void terminate_secondary() {
    if (secondary_terminated()) return;
    for (int i = 1; i < kMaxWavelengths; ++i) pdf_[i] = 0.f;
    pdf_[0] /= float(count_);
  }
  bool secondary_terminated() const {
    for (int i = 1; i < count_; ++i)
      if (pdf_[i] != 0.f) return false;
    return count_ > 1;
  }

 private:
  SampledSpectrum lambda_, pdf_;
  int count_ = 0;
};

}  // namespace chlorovdb
