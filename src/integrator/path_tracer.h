#pragma once
// The volumetric spectral path tracer (null-scattering formulation with
// spectral MIS, as pbrt-v4's VolPathIntegrator) extended with a fluorescence
// source term estimated along every ray segment inside a fluorescent medium.
#include "core/rng.h"
#include "integrator/excitation_routes.h"
#include "scene/scene.h"

namespace chlorovdb {

struct ContinuationOrigin;  // integrator/excitation_connection.h

// Radiance split by origin: light that went through at least one fluorescence
// event, and everything else. Their sum is the image.
struct PathRadiance {
  SampledSpectrum fluorescence;
  SampledSpectrum other;
};

// Counters for reports and tests (per thread, summed by the caller).
struct PathStats {
  uint64_t paths = 0;
  uint64_t fluorescence_points = 0;  // points drawn for an event, with or without pigment there
  uint64_t fluorescence_events = 0;  // those where the pigment is present
  uint64_t excitation_rays = 0;
  uint64_t excitation_continuations = 0;
  ExcitationRouteSums excitation_routes;  // the camera paths' events
};

struct PathOptions {
  // An excitation continuation (full mode) starts at a fluorescence event; the
  // light reaching it straight from the emitters is already counted by the
  // excitation ray, so its first segment ignores emitters.
  bool skip_emitters_on_first_segment = false;
  int fluorescence_depth = 0;  // nesting of excitation continuations
  // An excitation continuation: the event it left. With
  // excitation_through_glass = connect, the paths it walks from there through
  // glass alone to an area light count by their share against the excitation
  // connection (integrator/excitation_connection.h; paths are single-wavelength,
  // λ = lambda[0]); with origin->bounce, the straight light from a point, spot
  // or area light at the first diffuse vertex so reached (its shadow ray, or its
  // BSDF sample's hit on an area light) counts by its share against the bounce
  // connection (bounce_connection.h).
  const ContinuationOrigin* continuation_origin = nullptr;
  int max_segments = 1 << 16;  // hard bound on the loop (interfaces + collisions)
};

// Radiance arriving at ray.o from direction -ray.d, at the path's wavelengths.
// `medium` is the medium ray.o lies in (-1: vacuum). The path may terminate
// secondary wavelengths (dispersion), hence the non-const `lambda`.
PathRadiance trace_path(const Scene& scene, Ray ray, int medium, SampledWavelengths& lambda, Rng& rng,
                        PathStats& stats);
PathRadiance trace_path_from(const Scene& scene, Ray ray, int medium, SampledWavelengths& lambda, Rng& rng,
                             PathStats& stats, const PathOptions& options);

}  // namespace chlorovdb
