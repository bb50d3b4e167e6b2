#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fluorescence/excitation_grid.h"

using namespace chlorovdb;

namespace {

double total(const ExcitationGrid& g, int bin) {
  double sum = 0;
  const auto n = g.cells();
  const Vec3 size = g.region().diagonal();
  for (int iz = 0; iz < n[2]; ++iz)
    for (int iy = 0; iy < n[1]; ++iy)
      for (int ix = 0; ix < n[0]; ++ix) {
        const Vec3 centre = g.region().lo + Vec3{(ix + 0.5f) * size.x / n[0], (iy + 0.5f) * size.y / n[1],
                                                 (iz + 0.5f) * size.z / n[2]};
        sum += g.at(centre).values[bin];
      }
  return sum;
}

}  // namespace

// The track length a segment leaves in the grid is its length inside the region,
// split over the cells it crosses; nothing outside the region, nothing in other bins.
TEST(ExcitationGrid, DepositSplitsTheTrackLengthOverTheCellsItCrosses) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {1, 2, 1}}, {4, 8, 4});
  const int bin = ExcitationGrid::bin_of(420.f);
  // Along x through one row of cells: a quarter in each of four cells.
  g.deposit({-1.f, 0.1f, 0.1f}, {3.f, 0.1f, 0.1f}, bin, 2.f);
  for (int ix = 0; ix < 4; ++ix) EXPECT_NEAR(g.at({0.125f + 0.25f * ix, 0.1f, 0.1f}).values[bin], 0.5f, 1e-5f) << ix;
  EXPECT_EQ(g.at({0.125f, 0.3f, 0.1f}).values[bin], 0.f);  // the next row
  EXPECT_NEAR(total(g, bin), 2.0, 1e-5);
  EXPECT_EQ(total(g, bin + 1), 0.0);
  // Oblique, starting and ending inside: the whole length, whatever the cells.
  const Vec3 a{0.05f, 0.13f, 0.91f}, b{0.97f, 1.71f, 0.02f};
  g.deposit(a, b, bin, 1.f);
  EXPECT_NEAR(total(g, bin), 2.0 + distance(a, b), 1e-4);
  // Oblique, crossing the whole region from outside: the chord inside it.
  ExcitationGrid h(Bounds3{{0, 0, 0}, {1, 1, 1}}, {5, 3, 7});
  h.deposit({-1.f, -1.f, -1.f}, {2.f, 2.f, 2.f}, 0, 1.f);
  EXPECT_NEAR(total(h, 0), std::sqrt(3.0), 1e-4);
  EXPECT_EQ(h.at({1.5f, 0.5f, 0.5f}).values, nullptr);
}

TEST(ExcitationGrid, BinsCoverTheExcitationRange) {
  EXPECT_EQ(ExcitationGrid::bin_of(kLambdaMinUV), 0);
  EXPECT_EQ(ExcitationGrid::bin_of(kLambdaMax), ExcitationGrid::kBins - 1);
  for (int b = 0; b < ExcitationGrid::kBins; ++b) EXPECT_EQ(ExcitationGrid::bin_of(ExcitationGrid::bin_center(b)), b);
}

// Values are tallies over the medium's share of each cell: a cell half filled
// reads twice what the same tally over the whole cell would.
TEST(ExcitationGrid, NormalizeDividesByTheMediumsVolumeInEachCell) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {2, 1, 1}}, {2, 1, 1});
  g.deposit({0.f, 0.5f, 0.5f}, {2.f, 0.5f, 0.5f}, 3, 8.f);  // 8 in each cell
  g.add_medium_volume({0.f, 0.5f, 0.5f}, {1.f, 0.5f, 0.5f}, 1.f);  // the first cell, whole
  g.add_medium_volume({1.f, 0.5f, 0.5f}, {1.5f, 0.5f, 0.5f}, 1.f);  // half the second
  g.normalize(4.0);
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[3], 8.f / 4.f / 1.f, 1e-5f);
  EXPECT_NEAR(g.at({1.5f, 0.5f, 0.5f}).values[3], 8.f / 4.f / 0.5f, 1e-5f);
}

// Medium lines along x over [0, x_end] × the unit square (lines² of them), each
// tallying `fluence` (a function of x) by `steps` short segments into bin 0.
template <typename Fluence>
void tally_lines_along_x(ExcitationGrid& g, float x_end, int lines, int steps, Fluence fluence) {
  const float area = 1.f / float(lines * lines), step = x_end / float(steps);
  for (int j = 0; j < lines; ++j)
    for (int k = 0; k < lines; ++k) {
      const float y = (j + 0.5f) / lines, z = (k + 0.5f) / lines;
      g.add_medium_volume({0.f, y, z}, {x_end, y, z}, area);
      for (int i = 0; i < steps; ++i) {
        const float x0 = i * step, x1 = x0 + step;
        g.deposit({x0, y, z}, {x1, y, z}, 0, area * fluence(0.5f * (x0 + x1)));
      }
    }
}

// A fluence that varies linearly, f = 1 + 2x, tallied by short segments along x
// over a medium that fills the first cell and half the second: each cell keeps its
// average over the medium's part, and its profile at any point of that part gives
// back f there.
TEST(ExcitationGrid, TheProfileReproducesALinearFluenceInsideEachCell) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {2, 1, 1}}, {2, 1, 1});
  tally_lines_along_x(g, 1.5f, 16, 600, [](float x) { return 1.f + 2.f * x; });
  g.normalize(1.0);
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[0], 2.f, 1e-3f);   // the mean of f over [0, 1]
  EXPECT_NEAR(g.at({1.25f, 0.5f, 0.5f}).values[0], 3.5f, 1e-3f);  // over [1, 1.5]
  for (const float x : {0.05f, 0.3f, 0.7f, 0.95f, 1.05f, 1.25f, 1.45f}) {
    const ExcitationGrid::Lookup l = g.at({x, 0.3f, 0.8f});
    EXPECT_NEAR(l.profile * l.values[0], 1.f + 2.f * x, 2e-3f) << "x = " << x;
  }
}

// A fluence that falls e-fold in a tenth of the cell: its linear fit would go
// negative across most of the cell, so the limiter scales the slope until the
// profile is zero at the far face. The profile stays non-negative, its mean over
// the medium stays 1 (the cell keeps its average; clamping the unlimited slope,
// −4.8 per cell, at zero would raise it to 1.20) and it is 2 at the lit face.
TEST(ExcitationGrid, TheSlopeLimiterKeepsTheCellsAverageAndTheProfileNonNegative) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1});
  tally_lines_along_x(g, 1.f, 8, 1000, [](float x) { return std::exp(-10.f * x); });
  g.normalize(1.0);
  double mean = 0;
  constexpr int kSamples = 1000;
  for (int i = 0; i < kSamples; ++i) {
    const float profile = g.at({(i + 0.5f) / kSamples, 0.5f, 0.5f}).profile;
    EXPECT_GE(profile, 0.f);
    mean += profile / kSamples;
  }
  EXPECT_NEAR(mean, 1.0, 2e-3);
  EXPECT_NEAR(g.at({0.f, 0.5f, 0.5f}).profile, 2.f, 2e-3f);
  EXPECT_NEAR(g.at({1.f - 1e-6f, 0.5f, 0.5f}).profile, 0.f, 2e-3f);
}

// A pigment held in a thin sheet across the cell (a tenth of it thick, like a
// leaf's blade in a photon cell) under light that falls 2.8 e-folds across the
// sheet and is unattenuated around it: tallies weighted by concentration
// (Measure::amount) read the mean fluence inside the sheet, 0.335 of the light
// above it; weighted by volume the cell read the light around the sheet.
TEST(ExcitationGrid, ASheetOfPigmentReadsTheFluenceInsideIt) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1}, ExcitationGrid::Measure::amount);
  constexpr float kBottom = 0.45f, kThickness = 0.1f, kFall = 2.8f / kThickness;
  const auto inside = [&](float z) { return z >= kBottom && z <= kBottom + kThickness; };
  // Light from +z: 1 above the sheet, falling through it, e^-2.8 below.
  const auto fluence = [&](float z) { return std::exp(-kFall * std::clamp(kBottom + kThickness - z, 0.f, kThickness)); };
  constexpr int kLattice = 200;
  constexpr float kSide = 1.f / kLattice;
  // Lines along x on a lattice in y and z; ∫ c along each is exact (c = 2 inside).
  for (int j = 0; j < kLattice; ++j)
    for (int k = 0; k < kLattice; ++k) {
      const float y = (j + 0.5f) * kSide, z = (k + 0.5f) * kSide;
      g.deposit_weighted({0.f, y, z}, {1.f, y, z}, 0, kSide * kSide * fluence(z), [&](const Vec3& a, const Vec3& b) {
        return ExcitationGrid::LineIntegral{inside(z) ? 2.f * distance(a, b) : 0.f, 0.5f * (a + b)};
      });
      if (inside(z)) g.add_pigment_amount({0.5f, y, z}, 2.f * kSide * kSide, Vec3{0.5f, 0.5f * kSide, 0.5f * kSide});
    }
  g.normalize(1.0);
  const float mean = (1.f - std::exp(-2.8f)) / 2.8f;
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[0], mean, 0.01f * mean);
}
