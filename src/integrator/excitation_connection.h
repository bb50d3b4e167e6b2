#pragma once
// The excitation ray's connection to a light through glass (specular paths
// solved from the event, specular_connection.h) and how it shares those paths
// with `full` mode's excitation continuation, which walks the same ones when
// it refracts into an area light.
//
// Per unit solid angle at the event x and per nm, the two densities of one
// path x → glass → y on area light l at λ':
//   connection:   P_s · pmf_pigment(l) · p(λ' | l) · pdf_A(y) / (dω_0/dA_⊥ · |cos θ_y|)
//   continuation: P_continue · p_λ''(λ') · p_ω(x, ω_0) · Π F_i
// (Π F_i: the probability that the path tracer's dielectrics choose those
// events; transmittance left out, the same in both). P_s = 1 for a path a
// deterministic chain solves. A random seed finds a path with the seed's
// probability times SMS's p(S), which nothing knows; P_s puts
// kSeedFindProbability in its place (a weight needs only to be a function of
// the path for the two to add up to 1). The power heuristic then gives paths
// with a large solid angle per area of the lamp (a caustic through a curved
// wall: the connection's tail, weighted by SMS's count) to the continuation,
// whose estimate of them is bounded by the lamp's radiance.
//
// SMS's count stops at N seeds, so the connection holds a seeded path with
// weight w · (1 − (1 − p)^N): the continuation keeps (1 − w) + w · [N fresh
// seeds miss it], running those seeds with probability w.
#include <optional>

#include "core/rng.h"
#include "fluorescence/fluorescent_pigment.h"
#include "integrator/specular_connection.h"

namespace chlorovdb {

// A fluorescence event as an excitation continuation starts from it: where it
// is, its pigment, the probability that a continuation leaves it (0: none
// does), and whether the bounce connection (bounce_connection.h) also sampled
// the light lit diffuse surfaces send it.
struct ContinuationOrigin {
  Vec3 x;
  int medium = -1;
  const FluorescentPigment* fp = nullptr;
  float p_continue = 0.f;
  bool bounce = false;
};

// The continuation's density of a path leaving x along w0 at λ with Π F_i =
// `fresnel`, per unit solid angle and per nm (the header's formula).
float continuation_path_density(const Scene& scene, const ContinuationOrigin& origin, const Vec3& w0, float lambda_nm,
                                float fresnel);

// The fluence rate at a medium point x (one wavelength: wl.count() == 1) that
// light_through_dielectrics finds from light `light_index` (its random seed at
// one connection in four for area lights, at every one for delta lights).
// With an `origin` that may continue, each path through glass to an area light
// is weighted by the connection's share against the continuation.
std::optional<float> connect_through_dielectrics(const Scene& scene, const Vec3& x, int medium, int light_index,
                                                 Point2 u, PreparedMedia& media, Rng& rng,
                                                 const ContinuationOrigin* origin = nullptr);

// The continuation's share of the path it walked from origin.x through the
// glass events `walked` alone to the point y (geometric normal ng) of area
// light `light_index` at λ: 1 − w for a path a deterministic chain solves,
// (1 − w) + w · [seeds miss it] for one the seeds can reach, 1 for any other.
float continuation_weight_against_connection(const Scene& scene, const ContinuationOrigin& origin,
                                             const SpecularChain& walked, const Vec3& y, const Vec3& ng,
                                             int light_index, float lambda_nm, Rng& rng);

}  // namespace chlorovdb
