#include <gtest/gtest.h>

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
        sum += g.at(centre)[bin];
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
  for (int ix = 0; ix < 4; ++ix) EXPECT_NEAR(g.at({0.125f + 0.25f * ix, 0.1f, 0.1f})[bin], 0.5f, 1e-5f) << ix;
  EXPECT_EQ(g.at({0.125f, 0.3f, 0.1f})[bin], 0.f);  // the next row
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
  EXPECT_EQ(h.at({1.5f, 0.5f, 0.5f}), nullptr);
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
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f})[3], 8.f / 4.f / 1.f, 1e-5f);
  EXPECT_NEAR(g.at({1.5f, 0.5f, 0.5f})[3], 8.f / 4.f / 0.5f, 1e-5f);
}
