#pragma once
// The fluorescence source term (docs/physics.md §3) along a camera path.
#include "core/rng.h"
#include "integrator/excitation_connection.h"
#include "integrator/path_tracer.h"
#include "integrator/transport.h"

namespace chlorovdb {

// Unbiased estimate of  ∫_0^{t_end} T(0,t,λ) j(x(t), λ) dt  for every carried λ:
// one point t on the segment, T by the scene's transmittance estimator, and
// j from one excitation sample (light, point on it, λ' ∝ S·ε·λ') that serves
// all carried wavelengths. In `full` mode an excitation continuation at λ'
// adds the fluence that scattered, reflected, refracted or was re-emitted;
// `continuations` counts those the calling path has spawned (it lowers the
// chance of spawning more, keeping the branching bounded).
// render.excitation_sampling = uniform draws λ' uniformly over the same band
// (the ExcitationSampler knows its mode); render.quantum_yield_mode = roulette
// keeps the event with probability Q at weight 1 instead of weighting it by Q.
// `routes`, if given, receives the estimate split by excitation route, every
// lane (they sum to the result).
SampledSpectrum estimate_fluorescence_along(const Scene& scene, const Ray& ray, float t_end, int medium,
                                            PreparedMedia& media, Rng& rng, PathStats& stats, int depth,
                                            int* continuations,
                                            std::array<SampledSpectrum, kExcitationRoutes>* routes = nullptr);

// Full mode continues an excitation path at an event with probability
//   P = 0.5^(depth + 1) / (1 + k)^2,
// depth the nesting level and k the continuations this path already spawned.
// Each coin is weighted by its own P (unbiased: k depends only on earlier
// coins). A fixed P made scattering media a supercritical branching process
// (every one of ~30 segments of a τ = 30 path spawning sub-paths that spawn
// again); with this P a path's expected offspring stays below 0.82 · 0.5^depth.
// Nesting is also capped at 8 so no recursion is unbounded.
float continuation_probability(int depth, int spawned);

// An excitation continuation's wavelength λ'': a mixture of the pigment's
// lights' excitation tables (75 %, by their selection probability), its
// reabsorption tables (20 %, emission·ε: re-emitted light is found where the
// bands overlap) and a uniform 5 % over 250–830 nm. Without reabsorption
// tables the lights take their share; without lights, the uniform part does.
// *pdf is the density.
float sample_continuation_wavelength(const FluorescentPigment& fp, Rng& rng, float* pdf);
// That mixture's density at λ (per nm).
float continuation_wavelength_pdf(const FluorescentPigment& fp, float lambda);
// Radiance at λ arriving at the event origin.x (in origin.medium) from
// direction w that an excitation continuation counts: no emitter on the first
// segment (the excitation ray counts those), the paths through glass to area
// lights by their share against the excitation connection
// (excitation_connection.h), the light lit diffuse surfaces send by its share
// against the bounce connection (origin.bounce); nested events at depth + 1.
// Training the continuation guides probes the same quantity. `reemitted`, if
// given, receives the part of it that fluorescence re-emitted on the way.
float continuation_radiance(const Scene& scene, const ContinuationOrigin& origin, const Vec3& w, float lambda, Rng& rng,
                            PathStats& stats, int depth, float* reemitted = nullptr);
// The solid-angle density of a continuation's direction w from x: the medium's
// continuation guide's, uniform over the sphere without one.
float continuation_direction_pdf(const Scene& scene, int medium, const Vec3& x, const Vec3& w);

// The thesis's estimator (docs/physics.md §5), kept to measure its bias and cost:
// called when the hero wavelength is absorbed at `p`; with probability Q it
// becomes a fluorescence event that samples λ_e uniformly below λ within the
// light's support and tests one free path toward the light. Neither
// render.excitation_sampling nor render.quantum_yield_mode changes it.
SampledSpectrum reference_fluorescence_event(const Scene& scene, const Vec3& p, int medium,
                                             const SampledSpectrum& beta,
                                             const SampledWavelengths& lambda, Rng& rng, PathStats& stats);

}  // namespace chlorovdb
