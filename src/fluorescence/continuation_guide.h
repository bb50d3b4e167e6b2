#pragma once
// Where an excitation continuation (full mode) sends its first direction.
//
// The continuation estimates the fluence at a fluorescence event x that did not
// come straight from a light: it leaves x in one direction and traces a path.
// Drawn uniformly over the sphere, that direction rarely finds the few bright
// things a vessel of liquid sees — the floor in front of a UV lamp, seen through
// the glass — and those few samples then carry weights of 10³× the mean
// (docs/fluorescence.md, "Where the error sits"). A guide is a coarse grid over
// the fluorescent medium whose cells hold a histogram of that indirect fluence
// over directions, learned before the render from probe paths (training:
// integrator/continuation_guide_training.h), in the spirit of Jensen's
// photon-map importance sampling (1995) and Vorba et al. (2014).
//
// The direction density is a mixture: uniform_share of the sphere, the rest the
// cell's histogram, so it is positive wherever the uniform one is and the
// estimator stays unbiased whatever the training learned.
#include <array>
#include <vector>

#include "core/sampling.h"
#include "core/vec.h"

namespace chlorovdb {

// Equal-area direction bins: cos θ (z) in kDirectionZBins equal steps, φ in
// kDirectionPhiBins, so every bin spans 4π / kDirectionBins sr.
constexpr int kDirectionZBins = 16, kDirectionPhiBins = 32;
constexpr int kDirectionBins = kDirectionZBins * kDirectionPhiBins;
int direction_bin(const Vec3& w);               // w unit
Vec3 direction_in_bin(int bin, Point2 u);       // uniform by solid angle inside the bin

struct DirectionSample {
  Vec3 w;
  float pdf;  // solid angle
};

class ContinuationGuide {
 public:
  ContinuationGuide() = default;  // no guide: uniform everywhere
  // bin_weights[c][b] ≥ 0: the learned fluence of cell c (x fastest, then y, z)
  // in direction bin b; a cell whose weights are all 0 is sampled uniformly.
  ContinuationGuide(const Bounds3& bounds, std::array<int, 3> cells,
                    const std::vector<std::vector<float>>& bin_weights, float uniform_share);

  bool empty() const { return cells_.empty(); }
  const Bounds3& bounds() const { return bounds_; }
  std::array<int, 3> cell_counts() const { return n_; }
  int cell_of(const Vec3& p) const;  // -1 outside the grid
  float uniform_share() const { return uniform_share_; }

  // u_mix picks uniform or guided; u the direction. The pdf is the mixture's.
  DirectionSample sample(const Vec3& x, float u_mix, Point2 u) const;
  float pdf(const Vec3& x, const Vec3& w) const;

 private:
  const Distribution1D* cell_distribution(const Vec3& x) const;

  Bounds3 bounds_;
  std::array<int, 3> n_{0, 0, 0};
  std::vector<Distribution1D> cells_;  // empty Distribution1D: no guide in that cell
  float uniform_share_ = 1.f;
};

}  // namespace chlorovdb
