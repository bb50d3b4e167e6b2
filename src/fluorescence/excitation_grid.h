#pragma once
// The pigment's absorbed excitation, tallied by photons traced from the lamps
// (integrator/excitation_photons.h) on a coarse grid over a fluorescent medium:
// per cell and per excitation-wavelength bin,
//   value = (1/V) Σ_photons flux · ℓ · λ' · ε(λ'),
// the track-length estimate of ∫_bin λ'·ε(λ')·Φ(λ') dλ' averaged over the part of
// the cell the medium fills (V: that volume, measured by lines cast through the
// cells, so a cell astride the vessel's wall is not diluted by the glass or air
// in it; Φ the fluence, W/(m²·nm)). A fluorescence event at x with concentration c
// then reads its absorbed "λ'·μ_a·Φ" as k·c(x)·value (k = ln 10 · 100, the
// molar-extinction conversion) times the cell's linear profile at x.
//
// The profile: a cell's value is an average, and a fluence that falls across
// the cell (UV entering a strongly absorbing liquid falls e-fold within a cell or
// two) makes the average wrong at every point, the more so where the camera's
// events crowd toward the lit face: a bias of order the cell size. So the photons
// also tally the first moment of their track length about the cell's centre, and
// the medium lines the first and second moments of the medium's own volume; in
// each cell the linear profile 1 + g·(x − μ) (μ the medium's centroid in the cell)
// whose first moment over the medium's part matches the tally's is the factor at
// x. Its mean over the medium is 1, so every cell keeps its average, and it is
// exact for a linear fluence (the remaining bias is of second order). Where the
// slope would take it below zero within the medium's extent in the cell (a steep
// fall, or few photons' noise) the slope is scaled down until its lowest value
// there is zero (a slope limiter, as in MUSCL schemes): clamping at zero instead
// raised the cell's average, a bias of up to +6 % at low photon counts.
// Consistent, not unbiased.
#include <array>
#include <vector>

#include "core/constants.h"
#include "core/vec.h"
#include "spectra/sampled.h"

namespace chlorovdb {

class ExcitationGrid {
 public:
  // Excitation-wavelength bins over [kLambdaMinUV, kLambdaMax]: the emission's
  // redistribution r(λ', λ) is evaluated at each bin's centre.
  static constexpr int kBins = 32;
  static int bin_of(float lambda_nm);
  static float bin_center(int bin);

  ExcitationGrid() = default;
  ExcitationGrid(const Bounds3& region, const std::array<int, 3>& cells);

  bool empty() const { return values_.empty(); }
  const Bounds3& region() const { return region_; }
  const std::array<int, 3>& cells() const { return n_; }

  // Adds value_per_length × (the length of segment a→b inside each cell) to `bin`.
  void deposit(const Vec3& a, const Vec3& b, int bin, float value_per_length);
  // Adds the volume a line segment a→b inside the medium stands for: its length in
  // each cell times the cross-section each such line represents, m².
  void add_medium_volume(const Vec3& a, const Vec3& b, float cross_section);
  // Element-wise sum of the tallies (per-chunk grids into one).
  void add(const ExcitationGrid& other);
  // Tallies to values: divided by `photons` and by the medium's volume in each cell
  // (the whole cell's where no medium volume was measured); the moments to each
  // cell's linear profile.
  void normalize(double photons);
  // The kBins values of the cell holding x (its averages over the medium's part;
  // nullptr outside the region) and the cell's linear profile at x, their factor.
  struct Lookup {
    const float* values = nullptr;
    float profile = 0.f;
  };
  Lookup at(const Vec3& x) const;
  // Cells are numbered x fastest, then y, then z.
  size_t cell_count() const { return medium_volume_.size(); }
  // A cell's values summed over the bins.
  double cell_total(size_t cell) const;
  // The photons' noise, measured by the tracing from its independent chunks before
  // normalize() (which scales it with the values): per cell, the standard error of
  // cell_total (same units as the tallies when set); relative_error() is their RMS
  // over the RMS of the totals, cells weighted by the tally they hold, as the image
  // weights them. 0 where not measured.
  void set_tally_errors(std::vector<float> errors);
  double cell_error(size_t cell) const { return cell < errors_.size() ? errors_[cell] : 0.0; }
  float relative_error() const { return relative_error_; }
  float cell_volume() const { return cell_size_.x * cell_size_.y * cell_size_.z; }

 private:
  int cell_index(int ix, int iy, int iz) const { return (iz * n_[1] + iy) * n_[0] + ix; }
  Vec3 cell_center(const std::array<int, 3>& c) const;
  Bounds3 region_;
  std::array<int, 3> n_{};
  Vec3 cell_size_;
  // add(index, length, midpoint minus the cell's centre) for every piece of a→b in a cell.
  template <typename F>
  void for_each_cell(const Vec3& a, const Vec3& b, F add) const;
  std::vector<float> values_;         // cells × kBins
  std::vector<float> medium_volume_;  // per cell, m³
  // Per cell, about its centre: the tally's first moment (all bins) and the
  // medium's first and (per-axis) second moments.
  std::vector<Vec3> tally_moment_, medium_moment_, medium_spread_;
  std::vector<Vec3> medium_lo_, medium_hi_;  // per cell, the medium's extent about the centre (the limiter's)
  // Per cell, from normalize(): the profile's centroid μ (about the centre) and
  // gradient g; empty before (a flat profile).
  struct Profile {
    Vec3 centroid, gradient;
  };
  std::vector<Profile> profiles_;
  std::vector<float> errors_;         // per cell: standard error of cell_total
  float relative_error_ = 0.f;
};

}  // namespace chlorovdb
