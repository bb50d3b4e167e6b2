#pragma once
// Excitation by light that a diffuse surface reflects, connected through glass:
// a spot lamp lights the floor beside a vessel, and the floor sends part of that
// light through the glass into the pigment. An excitation continuation from the
// event x finds such light only when its direction happens to refract onto the
// small lit patch (and then with a weight of ~10⁵ times its median: the tail of
// teapot_50uM_D65_UVB_aim2's fluorescence); this strategy samples it from the
// light's side.
//
// At a fluorescence event x (one in two, kBounceProbability in the .cpp): a point
// or spot light l of the pigment (as its excitation ray picks one), λ' from l's
// excitation table, a ray the light emits (its own density, light_emission.h)
// to the first surface z it meets; when z
// scatters diffusely, the paths the deterministic chains solve from x to z
// (paths_to_surface_point: the straight line through the glass, its prefixes,
// the vessel's walls) carry z's reflected light to x:
//   Φ̂ = Φ · T(l→z) · f_z(ω_x, ω_l) · |cos_ns| / |cos_ng| · Π F_i · T_legs · (n_x/n_z)² · dω_0/dA_z,
// Φ the ray's flux (I · falloff / p_ω).
//
// The continuation samples the same paths (x → glass → z, then z's shadow ray
// to l), so both are weighed by the balance heuristic on their densities at z
// per unit area, per nm:
//   bounce:        P_bounce · pmf_pigment(l) · p(λ' | l) · p_ω(l → z) · |cos θ_z,l| / d²(l, z)
//   continuation:  P_continue · p_λ''(λ') · p_ω(x, ω_0) · Π F_i · dω_0/dA_z · pmf_scene(l)
// (Π F_i: the probability that the path tracer's dielectrics choose those events;
// Russian roulette and transmittance left out, the same in both, so the weights
// add up to 1 on every path). Paths the chains do not solve (reflections, more
// faces, seeds' finds), area and distant lights stay with the continuation alone.
#include "core/rng.h"
#include "core/vec.h"
#include "integrator/excitation_connection.h"
#include "integrator/path_tracer.h"

namespace chlorovdb {

// One bounce sample at the event: λ'·μ_a·Φ absorbed at x per unit
// concentration-free weight (lp·k·ε(lp)·c·fluence / (pmf · p(λ'))), MIS-weighted,
// and the λ' it was drawn at. Zero when the light is not at a point, the ray
// meets no diffuse surface, or no path reaches x.
struct BounceExcitation {
  float absorbed = 0.f;
  float lambda = 0.f;
};
BounceExcitation bounce_excitation(const Scene& scene, const ContinuationOrigin& origin, float concentration, Rng& rng,
                                   PathStats& stats);

// The continuation's balance-heuristic weight for the light a diffuse point z
// (its hit) receives straight from light `light_index` at λ, when the
// continuation reached z from origin.x through the glass events `walked` alone.
// 1 when the bounce cannot sample that path.
float continuation_weight_against_bounce(const Scene& scene, const ContinuationOrigin& origin,
                                         const SpecularChain& walked, const SurfaceHit& z, int light_index,
                                         float lambda_nm);

}  // namespace chlorovdb
