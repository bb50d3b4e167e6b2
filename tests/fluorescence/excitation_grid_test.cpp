#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

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
  g.normalize(4.0, [](ExcitationGrid& m) {
    m.add_medium_volume({0.f, 0.5f, 0.5f}, {1.f, 0.5f, 0.5f}, 1.f);  // the first cell, whole
    m.add_medium_volume({1.f, 0.5f, 0.5f}, {1.5f, 0.5f, 0.5f}, 1.f);  // half the second
  });
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[3], 8.f / 4.f / 1.f, 1e-5f);
  EXPECT_NEAR(g.at({1.5f, 0.5f, 0.5f}).values[3], 8.f / 4.f / 0.5f, 1e-5f);
}

// Lines along x over [0, x_end] × the unit square (lines² of them), each tallying
// `fluence` (a function of x) by `steps` short segments into bin 0; then the grid
// normalized with the same lines as the medium.
template <typename Fluence>
void tally_lines_along_x(ExcitationGrid& g, float x_end, int lines, int steps, Fluence fluence) {
  const float area = 1.f / float(lines * lines), step = x_end / float(steps);
  auto for_each_line = [&](auto f) {
    for (int j = 0; j < lines; ++j)
      for (int k = 0; k < lines; ++k) f((j + 0.5f) / lines, (k + 0.5f) / lines);
  };
  for_each_line([&](float y, float z) {
    for (int i = 0; i < steps; ++i) {
      const float x0 = i * step, x1 = x0 + step;
      g.deposit({x0, y, z}, {x1, y, z}, 0, area * fluence(0.5f * (x0 + x1)));
    }
  });
  g.normalize(1.0, [&](ExcitationGrid& m) {
    for_each_line([&](float y, float z) { m.add_medium_volume({0.f, y, z}, {x_end, y, z}, area); });
  });
}

// Light absorbed on its way falls exponentially: f = e^(−3x), tallied by short
// segments along x over a medium that fills the first cell and half the second.
// Each cell keeps its average over the medium's part, and its profile at any point
// of that part gives back f there (a linear profile was off by up to 16 %).
TEST(ExcitationGrid, TheProfileReproducesAnExponentialFluenceInsideEachCell) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {2, 1, 1}}, {2, 1, 1});
  const auto f = [](float x) { return std::exp(-3.f * x); };
  tally_lines_along_x(g, 1.5f, 16, 600, f);
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[0], (1 - std::exp(-3.0)) / 3, 1e-4f);  // the mean over [0, 1]
  EXPECT_NEAR(g.at({1.25f, 0.5f, 0.5f}).values[0], (std::exp(-3.0) - std::exp(-4.5)) / 1.5, 1e-4f);  // over [1, 1.5]
  for (const float x : {0.05f, 0.3f, 0.7f, 0.95f, 1.05f, 1.25f, 1.45f}) {
    const ExcitationGrid::Lookup l = g.at({x, 0.3f, 0.8f});
    EXPECT_NEAR(l.profile * l.values[0] / f(x), 1.f, 2e-3f) << "x = " << x;
  }
}

// A fluence that falls e-fold in a tenth of the cell, and one 4 times steeper:
// beyond the steepest profile fitted (rate × the medium's half-width 2, a fall of
// e⁴ across it, so a few photons' noise cannot put a cell's whole value in a
// sliver of it, nor a cell holding a sliver of liquid read 10⁹ times its mean
// beside it) the profile is that bound. It stays positive, within e^±2 of its
// scale, and its mean over the medium is 1: the cell keeps its average (made so by
// the second pass, not by the fit).
TEST(ExcitationGrid, ASteepFallKeepsTheCellsAverageWithABoundedProfile) {
  for (const float rate : {10.f, 40.f}) {
    ExcitationGrid g(Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1});
    tally_lines_along_x(g, 1.f, 8, 4000, [&](float x) { return std::exp(-rate * x); });
    double mean = 0;
    float lowest = kInfinity, highest = 0.f;
    constexpr int kSamples = 4000;
    for (int i = 0; i < kSamples; ++i) {
      const float profile = g.at({(i + 0.5f) / kSamples, 0.5f, 0.5f}).profile;
      lowest = std::min(lowest, profile);
      highest = std::max(highest, profile);
      mean += profile / kSamples;
    }
    EXPECT_NEAR(mean, 1.0, 2e-3) << "rate " << rate;
    EXPECT_GT(lowest, 0.f);
    EXPECT_NEAR(highest / lowest, std::exp(4.f), 0.01f * std::exp(4.f)) << "rate " << rate;
  }
}

// A pigment held in a thin sheet across the cell at a slant (normal (1, 1, 0)/√2,
// 0.1 of the cell thick, like a leaf's blade in a photon cell), lit so that the
// fluence falls 2.8 e-folds across it, tallied by columns along z (in the sheet's
// plane) on a fine lattice in x and y: the outside ones tally light the pigment
// never sees, weighted out by c = 0.
struct SlantedSheet {
  static constexpr int kLattice = 400;
  static constexpr float kSide = 1.f / kLattice, kThickness = 0.1f, kFall = 2.8f / kThickness;
  const Vec3 normal = normalize(Vec3{1.f, 1.f, 0.f});
  float depth(const Vec3& p) const { return dot(p - Vec3{0.5f, 0.5f, 0.5f}, normal) + 0.5f * kThickness; }
  bool inside(const Vec3& p) const { const float t = depth(p); return t >= 0.f && t <= kThickness; }
  float fluence(const Vec3& p) const { return std::exp(-kFall * depth(p)); }
  float concentration(const Vec3& p) const { return inside(p) ? 2.f : 0.f; }
  template <typename F>
  void for_each_column(F f) const {
    for (int i = 0; i < kLattice; ++i)
      for (int j = 0; j < kLattice; ++j) f(Vec3{(i + 0.5f) * kSide, (j + 0.5f) * kSide, 0.5f});
  }
  static ExcitationGrid grid() { return {Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1}, ExcitationGrid::Measure::amount}; }
  void tally(ExcitationGrid& g, const Vec3& p) const {
    g.deposit_weighted({p.x, p.y, 0.f}, {p.x, p.y, 1.f}, 0, kSide * kSide * fluence(p),
                       [&](const Vec3& a, const Vec3& b) {
                         return ExcitationGrid::LineIntegral{concentration(p) * distance(a, b), 0.5f * (a + b)};
                       });
  }
  void normalize_by_its_amount(ExcitationGrid& g) const {
    g.normalize(1.0, [&](ExcitationGrid& m) {
      for_each_column([&](const Vec3& p) {
        if (inside(p)) m.add_pigment_amount(p, concentration(p) * kSide * kSide, Vec3{0.5f * kSide, 0.5f * kSide, 0.5f});
      });
    });
  }
  // The cell reads the mean fluence inside the sheet, and its profile the fluence at each depth.
  void expect_its_own_fluence(const ExcitationGrid& g) const {
    const float mean = (1.f - std::exp(-2.8f)) / 2.8f;
    EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[0], mean, 0.01f * mean);
    for (const float t : {0.1f, 0.3f, 0.5f, 0.7f, 0.9f}) {
      const Vec3 p = Vec3{0.5f, 0.5f, 0.3f} + (t - 0.5f) * kThickness * normal;
      const ExcitationGrid::Lookup l = g.at(p);
      EXPECT_NEAR(l.profile * l.values[0] / fluence(p), 1.f, 0.03f) << "depth " << t;
    }
  }
};

// The tallies weighted by concentration read the fluence inside the sheet, not the
// cell's, and the profile, fitted along the sheet's normal through the covariance
// of the pigment (per axis the slant spreads it over the whole cell and hides the
// fall), gives the fluence at each depth.
TEST(ExcitationGrid, AThinSlantedSheetOfPigmentReadsItsOwnFluenceAtEachDepth) {
  const SlantedSheet sheet;
  ExcitationGrid g = SlantedSheet::grid();
  sheet.for_each_column([&](const Vec3& p) { sheet.tally(g, p); });
  sheet.normalize_by_its_amount(g);
  sheet.expect_its_own_fluence(g);
}

// The same sheet tallied in 8 chunks, each a stripe of the sheet along its plane:
// the chunks' centroids differ widely along the sheet and not at all across it, so
// the profile's slope across it has no noise and is not shrunk. Taken per axis, the
// noise along the sheet leaked into the normal (the slant mixes x and y) and the
// profile came out flat: the leaves read 28 % low with photons.
TEST(ExcitationGrid, NoiseAlongASlantedSheetDoesNotFlattenTheProfileAcrossIt) {
  const SlantedSheet sheet;
  constexpr int kChunks = 8;
  std::vector<ExcitationGrid> chunks(kChunks, SlantedSheet::grid());
  const Vec3 along = normalize(Vec3{1.f, -1.f, 0.f});
  sheet.for_each_column([&](const Vec3& p) {
    // The sheet spans along ∈ [−√2/2, √2/2]: 8 stripes across that.
    const float s = dot(p - Vec3{0.5f, 0.5f, 0.5f}, along) / std::sqrt(2.f) + 0.5f;
    sheet.tally(chunks[size_t(std::clamp(int(s * kChunks), 0, kChunks - 1))], p);
  });
  ExcitationGrid g = ExcitationGrid::sum_of_chunks(std::move(chunks));
  sheet.normalize_by_its_amount(g);
  sheet.expect_its_own_fluence(g);
}

// A pigment held in a thin sheet across the cell (a tenth of it thick) under light
// that falls 2.8 e-folds across the sheet and is unattenuated around it: tallies
// weighted by concentration (Measure::amount) read the mean fluence inside the
// sheet, 0.335 of the light above it; weighted by volume the cell read the light
// around the sheet.
TEST(ExcitationGrid, ASheetOfPigmentReadsTheFluenceInsideIt) {
  ExcitationGrid g(Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1}, ExcitationGrid::Measure::amount);
  constexpr float kBottom = 0.45f, kThickness = 0.1f, kFall = 2.8f / kThickness;
  const auto inside = [&](float z) { return z >= kBottom && z <= kBottom + kThickness; };
  // Light from +z: 1 above the sheet, falling through it, e^-2.8 below.
  const auto fluence = [&](float z) { return std::exp(-kFall * std::clamp(kBottom + kThickness - z, 0.f, kThickness)); };
  constexpr int kLattice = 200;
  constexpr float kSide = 1.f / kLattice;
  auto for_each_line = [&](auto f) {
    for (int j = 0; j < kLattice; ++j)
      for (int k = 0; k < kLattice; ++k) f((j + 0.5f) * kSide, (k + 0.5f) * kSide);
  };
  // Lines along x on a lattice in y and z; ∫ c along each is exact (c = 2 inside).
  for_each_line([&](float y, float z) {
    g.deposit_weighted({0.f, y, z}, {1.f, y, z}, 0, kSide * kSide * fluence(z), [&](const Vec3& a, const Vec3& b) {
      return ExcitationGrid::LineIntegral{inside(z) ? 2.f * distance(a, b) : 0.f, 0.5f * (a + b)};
    });
  });
  g.normalize(1.0, [&](ExcitationGrid& m) {
    for_each_line([&](float y, float z) {
      if (inside(z)) m.add_pigment_amount({0.5f, y, z}, 2.f * kSide * kSide, Vec3{0.5f, 0.5f * kSide, 0.5f * kSide});
    });
  });
  const float mean = (1.f - std::exp(-2.8f)) / 2.8f;
  EXPECT_NEAR(g.at({0.5f, 0.5f, 0.5f}).values[0], mean, 0.01f * mean);
}
