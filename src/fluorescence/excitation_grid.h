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
// molar-extinction conversion) times the cell's profile at x.
//
// The profile: a cell's value is an average, and a fluence that falls across
// the cell (UV entering a strongly absorbing liquid falls e-fold within a cell or
// two; sunlight across a leaf's 0.2 mm blade, whatever the cell) makes the average
// wrong at every point, the more so where the camera's events crowd toward the
// lit face: a bias of order the fluence's fall across the cell. So the photons
// also tally the first moment of their track length about the cell's centre, and
// the medium's measure its first and second moments (a full covariance Σ: a
// leaf's blade crosses a cell at a slant). In each cell the profile is the
// exponential exp(κ·(x − μ)) (μ the medium's centroid in the cell), the shape of
// light absorbed on its way, whose first moment matches the tally's: its
// direction is the linear fit's, g = Σ⁻¹ (T₁/T − μ), and its rate along it
// solves the Langevin relation of an exponential over a uniform slab with the
// medium's spread along g (the linear fit where the fall is weak; exact for a
// Beer–Lambert fall along an axis of a filled cell). Its mean over the medium is
// then made exactly 1 by a second pass over the medium's measure (normalize()),
// so every cell keeps its average whatever shape the medium has in it. Bounds:
// the slope is shrunk toward flat by its signal-to-noise ratio (the photons'
// chunks measure the centroid's noise), and the rate times the medium's
// half-width along it is at most 2, the exponent clamped to ± that (a profile
// within e^±2 of its scale): unbounded, a cell holding a sliver of liquid got a
// rate fitted to the sliver's spread and the glass scenes came out 10⁴–10⁹ times
// too bright. The remaining bias is the fluence's departure from that shape.
//
// A pigment held in a grid (a leaf's 0.2 mm blade in its grid's box, a spill)
// fills part of a cell: the fluence its events need is the one inside the
// pigment, so there every tally is weighted by the concentration (value =
// ∫ c·λ'·ε·Φ dV / ∫ c dV; Measure::amount) and the moments are the pigment's,
// not the medium's volume's. Weighted by volume, the leaf's cells read the
// unattenuated light around its blade: +46 %.
// Consistent, not unbiased.
#include <algorithm>
#include <array>
#include <functional>
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

  // What a cell's tallies are averaged over: the volume the medium fills in it (a
  // pigment of constant concentration), or the amount of pigment in it, ∫ c dV in
  // mol/L·m³ (a pigment held in a grid, whose tallies are weighted by c).
  enum class Measure { volume, amount };

  ExcitationGrid() = default;
  ExcitationGrid(const Bounds3& region, const std::array<int, 3>& cells, Measure measure = Measure::volume);

  bool empty() const { return values_.empty(); }
  const Bounds3& region() const { return region_; }
  const std::array<int, 3>& cells() const { return n_; }

  Measure measure() const { return measure_; }

  // Adds value_per_length × (the length of segment a→b inside each cell) to `bin`.
  void deposit(const Vec3& a, const Vec3& b, int bin, float value_per_length);
  // The same weighted by a concentration field (Measure::amount): each piece y0→y1
  // of a→b in a cell adds value_per_length × line(y0, y1).integral, where `line`
  // returns an unbiased estimate of ∫ c along the piece (m·mol/L) and the point whose
  // offset stands for the piece in the first moment (the point the estimate looked
  // c up at: the estimate times it is unbiased for ∫ c·x along the piece).
  struct LineIntegral {
    float integral = 0.f;
    Vec3 at;
  };
  template <typename Line>
  void deposit_weighted(const Vec3& a, const Vec3& b, int bin, float value_per_length, Line&& line);
  // Adds the volume a line segment a→b inside the medium stands for: its length in
  // each cell times the cross-section each such line represents, m².
  void add_medium_volume(const Vec3& a, const Vec3& b, float cross_section);
  // Adds `amount` of pigment (Measure::amount: c·dV, mol/L·m³) spread evenly over
  // the box x ± half (per axis) inside one cell, the one holding x.
  void add_pigment_amount(const Vec3& x, float amount, const Vec3& half);

  // The cell holding x (x clamped into the region) and a cell's bounds.
  size_t cell_of(const Vec3& x) const;
  Bounds3 cell_bounds(size_t cell) const;
  // What add_medium_volume / add_pigment_amount have added to a cell (before normalize()).
  double medium_measure(size_t cell) const { return medium_volume_[cell]; }
  // Element-wise sum of the tallies (per-chunk grids into one).
  void add(const ExcitationGrid& other);
  // Tallies to values: divided by `photons` and by the medium's measure in each
  // cell (Measure::volume: the whole cell's where no medium volume was measured;
  // Measure::amount: a cell holding no pigment reads 0), and each cell's profile
  // fitted. `measure(grid)` adds the medium's measure (add_medium_volume or
  // add_pigment_amount); it is called twice and must add the same both times:
  // first for the measure and its moments, then for the profiles' normalization.
  void normalize(double photons, const std::function<void(ExcitationGrid&)>& measure);
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
  // The sum of grids of independent chunks of photons, whose spread measures the
  // photons' noise (before normalize(), which scales it with the values): per cell,
  // the standard error of cell_total (same units as the tallies), and that of the
  // tally's centroid, which normalize() weighs each profile's slope against (a slope
  // a few photons' noise could give is shrunk toward flat). relative_error() is the
  // cells' standard errors' RMS over the RMS of their totals, cells weighted by the
  // tally they hold, as the image weights them. 0 where not measured.
  static ExcitationGrid sum_of_chunks(std::vector<ExcitationGrid> chunks);
  double cell_error(size_t cell) const { return cell < errors_.size() ? errors_[cell] : 0.0; }
  float relative_error() const { return relative_error_; }
  float cell_volume() const { return cell_size_.x * cell_size_.y * cell_size_.z; }

 private:
  int cell_index(int ix, int iy, int iz) const { return (iz * n_[1] + iy) * n_[0] + ix; }
  Vec3 cell_center(const std::array<int, 3>& c) const;
  Vec3 cell_center(size_t cell) const;
  Bounds3 region_;
  std::array<int, 3> n_{};
  Vec3 cell_size_;
  Measure measure_ = Measure::volume;
  // add(index, t0, t1) for every piece [t0, t1] of the ray a + t·d (d = (b − a)/|b − a|)
  // inside one cell.
  template <typename F>
  void for_each_cell(const Vec3& a, const Vec3& b, F add) const;
  // Adds a tally to a bin and its first moment about the cell's centre, at y.
  void tally(size_t cell, int bin, float value, const Vec3& y) {
    values_[cell * kBins + size_t(bin)] += value;
    const Vec3 offset = y - cell_center(cell);
    for (int k = 0; k < 3; ++k) tally_moment_[cell][size_t(k)] += double(value) * offset[k];
  }
  // Adds a piece of the medium's measure: in the first pass its measure and
  // moments, in normalize()'s second the profile's integral over it.
  // `offset`: its centroid about the cell's centre; `spread`: its own second
  // moment about that centroid, per unit measure; `average_profile(rate)`: the
  // mean of exp(rate·(y − offset)) over the piece.
  template <typename AverageProfile>
  void add_measure(size_t cell, float measure, const Vec3& offset, const std::array<float, 6>& spread,
                   AverageProfile&& average_profile);
  std::vector<float> values_;         // cells × kBins
  std::vector<double> medium_volume_;  // per cell, the medium's measure: m³, or mol/L·m³ (Measure::amount)
  // Per cell, about its centre: the tally's first moment (all bins) and the
  // medium's (or pigment's) first and second moments (xx, yy, zz, xy, xz, yz). In
  // double: a steep profile's fit amplifies their rounding (25× at an e-fold per
  // tenth of the cell), and their terms cancel about the centre.
  std::vector<std::array<double, 3>> tally_moment_, medium_moment_;
  std::vector<std::array<double, 6>> medium_second_;
  // Per cell, from normalize(): the profile scale·exp(rate·(x − centre − centroid));
  // empty before (a flat profile).
  struct Profile {
    Vec3 centroid, rate;
    float scale = 1.f;
    float limit = 0.f;  // the exponent's bound: rate × the medium's half-width along it
  };
  std::vector<Profile> profiles_;
  std::vector<double> profile_integral_;  // normalize()'s second pass: per cell, ∫ exp(rate·(x − μ)) over the measure
  bool second_pass_ = false;
  std::vector<float> errors_;         // per cell: standard error of cell_total
  // Per cell: the covariance of the tally's centroid (xx, yy, zz, xy, xz, yz): a thin
  // sheet's centroid is sharp across it and noisy along it, so the noise along any
  // direction needs the off-diagonal terms.
  std::vector<std::array<double, 6>> centroid_covariance_;
  float relative_error_ = 0.f;
};

// Amanatides–Woo traversal over the cells the segment a→b crosses.
template <typename F>
void ExcitationGrid::for_each_cell(const Vec3& a, const Vec3& b, F add) const {
  const float length = distance(a, b);
  if (!(length > 0.f)) return;
  const Ray ray{a, (b - a) / length};
  float t0, t1;
  if (!intersect_bounds(region_, ray, length, &t0, &t1)) return;
  const Vec3 start = ray.at(t0 + 1e-4f * (t1 - t0));  // inside the first cell, not on its face
  std::array<int, 3> cell{}, step{};
  std::array<float, 3> t_next{}, t_delta{};
  for (int k = 0; k < 3; ++k) {
    cell[k] = std::clamp(int((start[k] - region_.lo[k]) / cell_size_[k]), 0, n_[k] - 1);
    const float dk = ray.d[k];
    if (dk > 0.f) {
      step[k] = 1;
      t_next[k] = (region_.lo[k] + float(cell[k] + 1) * cell_size_[k] - ray.o[k]) / dk;
      t_delta[k] = cell_size_[k] / dk;
    } else if (dk < 0.f) {
      step[k] = -1;
      t_next[k] = (region_.lo[k] + float(cell[k]) * cell_size_[k] - ray.o[k]) / dk;
      t_delta[k] = -cell_size_[k] / dk;
    } else {
      step[k] = 0;
      t_next[k] = kInfinity;
      t_delta[k] = kInfinity;
    }
  }
  float t = t0;
  while (t < t1) {
    const int k = t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
    const float t_exit = std::min(t_next[k], t1);
    if (t_exit > t) add(size_t(cell_index(cell[0], cell[1], cell[2])), t, t_exit);
    t = t_exit;
    cell[k] += step[k];
    if (cell[k] < 0 || cell[k] >= n_[k]) break;
    t_next[k] += t_delta[k];
  }
}

template <typename Line>
void ExcitationGrid::deposit_weighted(const Vec3& a, const Vec3& b, int bin, float value_per_length, Line&& line) {
  if (!(value_per_length > 0.f)) return;
  const Vec3 d = chlorovdb::normalize(b - a);
  for_each_cell(a, b, [&](size_t cell, float t0, float t1) {
    const LineIntegral l = line(a + t0 * d, a + t1 * d);
    if (l.integral > 0.f) tally(cell, bin, value_per_length * l.integral, l.at);
  });
}

}  // namespace chlorovdb
