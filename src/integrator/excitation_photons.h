#pragma once
// Light-traced excitation (render.excitation_estimate = photons): before the
// render, photons leave the lamps at excitation wavelengths λ' ∝ S·ε·λ' (each
// pigment's own light list and excitation samplers; a share of them aimed at the
// medium's bounding sphere, lights/light_emission.h), cross glass by its BSDF,
// scatter and bounce off surfaces, and are tracked through media by delta
// tracking; in a fluorescent medium every flight adds its track length to that
// pigment's ExcitationGrid (fluorescence/excitation_grid.h), and a photon the
// pigment absorbs is re-emitted at Q and goes on (its own fluorescence excites it
// where the bands overlap; other pigments' re-emission is not traced). Fluorescence
// events then read the absorbed excitation from the grid instead of tracing
// excitation rays: light that reached the pigment by any route (through glass, off
// the floor next to a lamp) costs one lookup. Consistent, not unbiased: the grid's
// cells average the fluence, and the photon count sets the grid's noise.
// docs/fluorescence.md measures both.
//
// Deterministic: fixed chunks of photons, each with its own random stream and
// grid, summed in order, so a render depends on its seed and samples only.
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fluorescence/excitation_grid.h"
#include "scene/scene.h"

namespace chlorovdb {

struct PhotonTracing {
  int64_t photons = 1 << 18;  // per fluorescent pigment of each medium
  int cells_per_axis = 32;    // along the medium's longest axis
  int max_bounces = 64;
  // Share of each light's photons aimed at the medium's bounding sphere
  // (lights/light_emission.h EmissionTarget); the rest follow the light's own density.
  float aimed_share = 0.5f;
  uint64_t seed = 0x70686f746f6e73ULL;  // prepare_excitation_grids mixes in the render's
};

// One grid per pigment (in FluorescentPigment order) per medium; empty where
// nothing fluoresces, no shape encloses the medium or no light excites it.
// `stop` (Ctrl-C) abandons the tracing: nullopt.
std::optional<std::vector<std::vector<ExcitationGrid>>> trace_excitation_photons(
    const Scene& scene, const PhotonTracing& tracing, const std::atomic<bool>* stop = nullptr);

// The photon settings in a line, for the log, the output's metadata and the
// checkpoint's signature: "262144 photons per pigment, 50% aimed, 32 cells".
std::string describe_excitation_photons(const RenderSettings& settings);

// The largest relative_error() of the scene's photon grids (0 before they are
// traced): the photons' noise a render carries whatever its samples per pixel.
float excitation_grid_error(const Scene& scene);

// Whether a render of this scene reads excitation from photon grids.
bool uses_excitation_photons(const Scene& scene);

// render() calls this first: traces scene.excitation_grids once (thread-safe)
// when uses_excitation_photons, and returns the seconds it took (0 if already done).
// The photons' streams come from the render's seed, so renders with different seeds
// have independent grids (their average converges; the grid's noise is part of each
// render's variance), and the parts of one render (crops, ranks, resumes) share one.
// Stopped by `stop`, it leaves no grids (the render then stops before its first pass).
double prepare_excitation_grids(const Scene& scene, uint64_t seed, const std::atomic<bool>* stop = nullptr);

}  // namespace chlorovdb
