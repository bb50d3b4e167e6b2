#pragma once
// Excitation by light that a diffuse surface reflects, connected through glass:
// a lamp lights the floor beside a vessel, and the floor sends part of that light
// through the glass into the pigment. An excitation continuation from the event x
// finds such light only when its direction happens to refract onto the lit patch
// (and then with a weight of ~10⁵ times its median: the tail of
// teapot_50uM_D65_UVB_aim2's fluorescence, and 92 % of the continuations' second
// moment on scenes/default.json, whose UVB panel lights the floor beside the
// cuvette); this strategy samples it from the light's side.
//
// At a fluorescence event x (one in two, kBounceProbability in the .cpp): a point,
// spot or area light l of the pigment (as its excitation ray picks one), λ' from
// l's excitation table, a ray the light emits (its own density, light_emission.h:
// area lights from a point y uniform by area, cosine-weighted) to the first
// surface z it meets; when z scatters diffusely, the paths the deterministic
// chains solve from x to z (paths_to_surface_point: the straight line through the
// glass, its prefixes, the vessel's walls) carry z's reflected light to x:
//   Φ̂ = Φ · T(l→z) · f_z(ω_x, ω_l) · |cos_ns| / |cos_ng| · Π F_i · T_legs · (n_x/n_z)² · dω_0/dA_z,
// Φ the ray's flux (I · falloff / p_ω; area lights Le·|cos θ_y| / (p_A · p_ω)).
//
// The continuation samples the same paths (x → glass → z, then z's shadow ray to
// l or, for an area light, z's BSDF sample that hits it), so the strategies are
// weighed by the balance heuristic on their densities per unit area at z (and at
// y for area lights), per nm:
//   bounce:        P_bounce · pmf_pigment(l) · p(λ' | l) · p_ω(l → z) · |cos θ_z,l| / d²(l, z)   [· p_A(y)]
//   continuation:  P_continue · p_λ''(λ') · p_ω(x, ω_0) · Π F_i · dω_0/dA_z
//                  · (pmf_scene(l)   [· p_A(y) + p_bsdf(z → y) · |cos θ_y| / d²])
// (Π F_i: the probability that the path tracer's dielectrics choose those events;
// Russian roulette and transmittance left out). The continuation multiplies both
// its shadow ray's and its BSDF hit's contributions (already weighed against each
// other by the path tracer) by its share, the bounce by its own, so the weights
// add up to 1 on every path. Paths the chains do not solve (reflections, more
// faces, seeds' finds), light reaching z through glass, and distant and
// environment lights stay with the continuation alone.
#include "core/rng.h"
#include "core/vec.h"
#include "integrator/excitation_connection.h"
#include "integrator/path_tracer.h"

namespace chlorovdb {

// One bounce sample at the event: λ'·μ_a·Φ absorbed at x per unit
// concentration-free weight (lp·k·ε(lp)·c·fluence / (pmf · p(λ'))), MIS-weighted,
// and the λ' it was drawn at. Zero when the light is distant or an environment,
// the ray meets no diffuse surface, or no path reaches x.
struct BounceExcitation {
  float absorbed = 0.f;
  float lambda = 0.f;
};
BounceExcitation bounce_excitation(const Scene& scene, const ContinuationOrigin& origin, float concentration, Rng& rng,
                                   PathStats& stats);

// Where the light meets the path after z: its point (a point or spot light's
// position), its geometric normal (area lights), and the density of z's BSDF
// sampling the direction toward it (area lights, whose BSDF hit is the
// continuation's second way to it).
struct LightVertex {
  Vec3 p, n;
  float bsdf_pdf = 0.f;
};

// The continuation's balance-heuristic share of the light a diffuse point z (its
// hit) receives straight from light `light_index` at λ (at `y`), when the
// continuation reached z from origin.x through the glass events `walked` alone.
// 1 when the bounce cannot sample that path.
float continuation_weight_against_bounce(const Scene& scene, const ContinuationOrigin& origin,
                                         const SpecularChain& walked, const SurfaceHit& z, int light_index,
                                         float lambda_nm, const LightVertex& y);

}  // namespace chlorovdb
