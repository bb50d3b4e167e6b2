#pragma once
// Spectrum: a function of wavelength in nm, as a value type. Variants: constant,
// tabulated (piecewise linear between samples, zero outside the table: tables
// are never extrapolated), blackbody (Planck, normalised to peak 1), Gaussian.
// Every spectrum carries a scale and a human-readable provenance string.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "spectra/sampled.h"

namespace chlorovdb {

// Largest |value| a tabulated spectrum accepts (its integral must stay finite in float).
inline constexpr float kMaxTabulatedValue = 1e30f;

class Spectrum {
 public:
  struct Constant {
    float value;
  };
  struct Tabulated {
    std::vector<float> lambda;  // strictly increasing, nm
    std::vector<float> value;
    // locate()'s O(1) index guess: cell k = ⌊(λ − lambda[0]) · inv_cell⌋. Evenly spaced
    // tables: one cell per segment, the cell is the segment. Others: two cells per
    // segment on average, and guide[k] is the segment the cell's start lies in.
    float inv_cell = 0.f;  // 1/nm
    std::vector<uint32_t> guide;  // empty for evenly spaced tables
    // Where lambda_nm lies: in segment [lambda[i], lambda[i+1]] at fraction x, so that
    // the spectrum there is (1 - x) value[i] + x value[i+1]. Nothing outside the table (or NaN).
    struct Position {
      size_t i;
      float x;
    };
    std::optional<Position> locate(float lambda_nm) const;
  };
  struct Blackbody {
    float temperature_K;
    float normalisation;  // 1 / peak value
  };
  struct Gaussian {
    float mean_nm, sigma_nm;
  };

  Spectrum() : rep_(Constant{0.f}) {}
  static Spectrum constant(float value);
  // Throws std::invalid_argument if lambda is not strictly increasing, sizes
  // differ, fewer than 2 samples, or a value is not finite.
  static Spectrum tabulated(std::vector<float> lambda, std::vector<float> value, std::string source = {});
  static Spectrum blackbody(float temperature_K);
  static Spectrum gaussian(float mean_nm, float sigma_nm, float peak = 1.f);

  float operator()(float lambda_nm) const;
  SampledSpectrum sample(const SampledWavelengths& lambda) const;
  Spectrum scaled(float s) const;

  float scale() const { return scale_; }
  float max_value() const;  // over [kLambdaMinUV, kLambdaMax] (or the table)
  // Wavelength interval outside which the spectrum is zero (constant/blackbody:
  // [kLambdaMinUV, kLambdaMax] — the range the renderer considers at all).
  float support_min() const;
  float support_max() const;
  // Integral over [a, b] in nm, exact for tabulated and constant spectra.
  float integral(float a, float b) const;
  const std::string& source() const { return source_; }
  const auto& representation() const { return rep_; }

 private:
  std::variant<Constant, Tabulated, Blackbody, Gaussian> rep_;
  float scale_ = 1.f;
  std::string source_;
};

}  // namespace chlorovdb
