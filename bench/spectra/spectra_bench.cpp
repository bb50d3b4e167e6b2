// Per-sample spectral costs: table lookups (evenly spaced: O(1) index; irregular: a
// guide table's index, walked), drawing hero wavelengths (the eye's closed form; a
// scene's mixture through its guide table), and the film's XYZ estimate for one path.
#include <benchmark/benchmark.h>

#include <vector>

#include "core/rng.h"
#include "spectra/color.h"
#include "spectra/library.h"
#include "spectra/wavelength_sampling.h"

using namespace chlorovdb;

namespace {

// Wavelengths drawn up front, so the timings below exclude sampling them.
std::vector<SampledWavelengths> wavelength_sets() {
  std::vector<SampledWavelengths> sets;
  Rng rng(1, 0);
  for (int i = 0; i < 1024; ++i) sets.push_back(SampledWavelengths::sample_visible(rng.uniform(), 4));
  return sets;
}

void lookup(benchmark::State& state, const char* name) {
  const Spectrum s = named_spectrum(name);
  const std::vector<SampledWavelengths> sets = wavelength_sets();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.sample(sets[i++ & 1023]));
}

void BM_LookupUniformStep(benchmark::State& state) { lookup(state, "D65"); }             // 1 nm, 531 rows
void BM_LookupIrregularStep(benchmark::State& state) { lookup(state, "chlorophyll_a"); }  // ~0.19 nm, 2562 rows

void BM_SampleVisibleFourLanes(benchmark::State& state) {
  Rng rng(2, 0);
  for (auto _ : state) benchmark::DoNotOptimize(SampledWavelengths::sample_visible(rng.uniform(), 4));
}

// A scene's camera-wavelength mixture: the eye's density, a lamp with mercury lines, a daylight.
void BM_SampleMixtureFourLanes(benchmark::State& state) {
  const Spectrum lamp = named_spectrum("F2"), daylight = named_spectrum("D65");
  const WavelengthDistribution d = WavelengthDistribution::mixture(
      {{[](float l) { return double(visible_wavelength_pdf(l)); }, 0.5},
       {[&](float l) { return double(lamp(l)); }, 0.25},
       {[&](float l) { return double(daylight(l)); }, 0.25}});
  Rng rng(3, 0);
  for (auto _ : state) benchmark::DoNotOptimize(d.sample(rng.uniform(), 4));
}

void BM_ToXyzFourLanes(benchmark::State& state) {
  const SampledSpectrum L(1.f);
  const std::vector<SampledWavelengths> sets = wavelength_sets();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(to_xyz(L, sets[i++ & 1023]));
}

}  // namespace

BENCHMARK(BM_LookupUniformStep);
BENCHMARK(BM_LookupIrregularStep);
BENCHMARK(BM_SampleVisibleFourLanes);
BENCHMARK(BM_SampleMixtureFourLanes);
BENCHMARK(BM_ToXyzFourLanes);
