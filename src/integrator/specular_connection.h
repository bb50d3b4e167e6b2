#pragma once
// Connections through smooth dielectric surfaces: from a point in a medium
// (excitation rays) or a scattering point on a surface or in a medium (camera
// paths' next-event estimation toward delta lights: the caustic on a floor) to a
// point, spot, distant or area light through a chain of up to kMaxRefractedChain
// dielectric faces (kMaxSpecularChain for the walls as mirrors), each crossed or
// mirrored, by solving for the specular path
// at the hero wavelength (Sellmeier glass bends each λ by its own index).
//
// The first chain is the straight line's from the point x to the light point
// y: the dielectric faces it crosses, in order; the walls of x's vessel give
// more, crossed or, where they would totally reflect the light, as mirrors
// (deterministic_chains). Two solvers, one per geometry:
// - all faces crossed, parallel planes (box faces, flat-shaded triangles):
//   Snell's invariant s = n_i sin θ_i, a 1-D monotone root, exact and unique
//   (the optical path length is strictly convex);
// - anything else on meshes and boxes (smooth-shaded triangles, non-parallel
//   planes, reflections): manifold next-event estimation (Hanika, Droske &
//   Fascione 2015; the Newton walk of Zeltner, Georgiev & Jakob 2020),
//   specular_manifold.cpp. It finds the solution its seed converges to, if any.
// A solved path counts only if each leg really reaches its face and nothing else.
//
// Other solutions, for every light, come from SMS's unbiased estimate: one
// random seed chain (a direction from x scattered on through the glass as the
// glass would: reflected with probability R; SeedPolicy can keep it to
// refraction), each solution it finds weighted by the number of further seeds
// it takes to find it again. So the light a beaker's wall mirrors out of its
// free surface, or bends in beside the straight line, is found where the
// straight line crosses other faces.
//
// Sharing with the other strategies that reach an area light through glass
// (BSDF-sampled camera paths, `full` mode's excitation continuations): a path
// the other strategy walks from x to y through specular glass events only is
// compared with what the deterministic chains (the straight line's, its
// prefixes, the walls of x's vessel crossed and mirrored: deterministic_chains) solve from x to y
// (same shapes, vertices within tolerance: solved_deterministically); the
// random seeds' share of a path is 1 − (1 − p)^N (seed_reachable_solution,
// seeds_miss). Camera paths drop what the chains solve; excitation
// continuations share by the power heuristic (excitation_connection.h).
// Continuations keep the paths no seed converges to (more than
// kMaxRefractedChain faces but the mirrors', spheres). Delta lights have no second strategy:
// those paths are not found (docs/fluorescence.md).
#include <array>
#include <optional>
#include <span>

#include "core/rng.h"
#include "integrator/transport.h"

namespace chlorovdb {

// Faces of the chains the straight line, the walls and the random seeds walk:
// longer seed chains find rare paths whose SMS estimate has relative variance
// ≈ 2/p (docs/fluorescence.md, "What reaches the lamp through the glass").
constexpr int kMaxRefractedChain = 4;
// Faces of any chain: a wall as a mirror doubles back through the face before it
// (a cuvette's floor: two faces down, one back, two out).
constexpr int kMaxSpecularChain = 5;

// ---- Refraction through parallel planes (plane of incidence) ----
// Layer i has thickness h[i] along the common normal and refractive index n[i]
// (absolute or relative to any common reference); layer 0 holds the start point,
// the last layer the end point. s = n_i sin θ_i is the same in every layer.

// Lateral distance covered: r(s) = Σ h_i s / sqrt(n_i² − s²).
double planar_lateral_offset(std::span<const double> h, std::span<const double> n, double s);
// The s with r(s) = lateral: r is convex and increasing on [0, min n_i), so
// Newton from s = 0 converges monotonically. nullopt if it does not converge.
std::optional<double> solve_planar_invariant(std::span<const double> h, std::span<const double> n, double lateral);
// Generalised geometry term dω_0 / dA_⊥: the solid angle at the start point per
// unit area perpendicular to the last leg at the end point,
//   1 / (n_0² · (r/s) · r'(s) · cos θ_0 · cos θ_last)
// (rotational symmetry about the normal: dA_plane = r dr dφ, dω_0 = sin θ_0 dθ_0 dφ).
// With one index everywhere it is 1/d².
double planar_solid_angle_per_area(std::span<const double> h, std::span<const double> n, double s);

// ---- Chains in a scene ----
// A dielectric face met: the shape, the triangle (or box face) and its plane
// (geometric normal, offset dot(ng, p)), where the path meets it, and whether
// it reflects there (a mirror vertex) instead of crossing.
struct ChainFace {
  int shape_id = -1, prim_id = -1;
  Vec3 ng;
  float offset = 0.f;
  Vec3 p;
  bool reflect = false;
};
struct SpecularChain {
  std::array<ChainFace, kMaxSpecularChain> faces;
  int count = 0;
  bool planar_parallel = true;  // all faces crossed, flat-shaded planes with parallel normals
};

// The dielectric faces crossed by the straight line from x toward y (or along
// y as a direction to infinity). nullopt when an opaque surface is crossed or
// more than kMaxRefractedChain dielectric faces are.
std::optional<SpecularChain> straight_line_chain(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity);

// The solved specular path: its vertices (face[j].p, on the triangle face[j]
// names, with the shading normal ns[j] there), leg directions toward the light,
// the layers' relative indices and the generalised geometry term.
struct RefractedPath {
  int count = 0;
  std::array<ChainFace, kMaxSpecularChain> face;
  std::array<Vec3, kMaxSpecularChain> ns;
  std::array<Vec3, kMaxSpecularChain + 1> dir;
  std::array<double, kMaxSpecularChain + 1> n;
  // Finite end: dω_0 / dA_⊥, the solid angle at x per unit area perpendicular
  // to the last leg at y. Distant light: dA_⊥(beam) / dA_⊥(x), the beam's
  // cross-section far away per cross-section at x (power conservation).
  double geometry = 0;
};
// A solved vertex as a surface hit (for spawning the next leg off it).
SurfaceHit solved_vertex_hit(const ChainFace& f, const Vec3& ns);

// Through the seed chain from x to the point y, or leaving toward the direction
// y (to_infinity). Relative indices from the chain's dielectrics at `lambda_nm`.
// Planar-parallel chains take the closed form, others the manifold solver.
// nullopt when no path is found (or the chain holds a sphere).
std::optional<RefractedPath> solve_refracted_path(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                  const Vec3& y, bool to_infinity, float lambda_nm);
// The manifold solver alone (any chain of mesh or box faces; tests compare it
// with the closed form on planar chains).
std::optional<RefractedPath> solve_manifold_path(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                 const Vec3& y, bool to_infinity, float lambda_nm);
// Whether the chain arrives at face j from outside its shape: the step from the
// previous vertex (x for j = 0) to face j's point runs against its outward normal.
bool chain_enters(const SpecularChain& chain, int j, const Vec3& x);
// Relative index n_i of every layer (n_0 = 1 at x): entering a face multiplies
// by its IOR, leaving divides by it, a reflection keeps it.
std::array<double, kMaxSpecularChain + 1> chain_indices(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                        float lambda_nm);

// SMS's random seed (Zeltner, Georgiev & Jakob 2020): the faces met by the ray
// from x along d, reflected or refracted at every dielectric face as a
// smooth dielectric would scatter it (reflection with the Fresnel probability
// R at the shading normal, at `lambda_nm`; always under total internal
// reflection), up to the leg that passes the light point y (to_infinity: the
// leg that leaves the scene). Without `reflect_too` it refracts only. nullopt
// when the ray meets an opaque surface (or, refracting only, total internal
// reflection) first, never passes y, meets more than kMaxRefractedChain faces
// or none.
std::optional<SpecularChain> specular_seed_chain(const Scene& scene, const Vec3& x, const Vec3& d, const Vec3& y,
                                                 bool to_infinity, float lambda_nm, bool reflect_too, Rng& rng);
// One random seed: a direction from x (half in the 30° cone around the straight
// line to y, half toward a point uniform by area on a dielectric shape), its
// specular_seed_chain, and the path the solver converges to from there, if any.
std::optional<RefractedPath> solve_from_random_seed(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity,
                                                    float lambda_nm, bool reflect_too, Rng& rng);

// The chains the connection solves deterministically from x toward the light
// point y (or the direction y, to_infinity): the straight line's chain; for area
// lights, each of its prefixes that ends in the medium the whole chain ends in
// (a path refracted at the first faces can pass beside the others: out of a
// beaker's free surface and over the rim the straight line clips); and, when the
// straight line crosses glass, the walls of x's vessel along the world axes
// toward the light whose faces are flat and parallel (a cuvette's side walls,
// lid and floor: the light a side panel sends in through the lid or the front
// wall at a grazing angle), and, for a light at a point, those walls along the
// axes away from the light as mirrors where they would totally reflect it (a
// cuvette's floor: the light mirrored up into the liquid near it). Empty when
// the straight line meets an opaque surface.
struct DeterministicChains {
  static constexpr int kMax = 1 + (kMaxRefractedChain - 1) + 3 + 3;
  std::array<SpecularChain, kMax> chains;
  int count = 0;
};
DeterministicChains deterministic_chains(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity,
                                         bool area_light, float lambda_nm);
// A path a continuation walked from x at λ (specular glass events at `walked`,
// then the area light at y): true when the solve of one of the connection's
// deterministic chains returns it.
bool solved_deterministically(const Scene& scene, const Vec3& x, const Vec3& y, const SpecularChain& walked,
                              float lambda_nm);
// The solved path of that deterministic chain, for any walk (also one through
// no glass: the straight line); nullopt when no deterministic chain returns it.
std::optional<RefractedPath> deterministic_solution(const Scene& scene, const Vec3& x, const Vec3& y,
                                                    const SpecularChain& walked, float lambda_nm);
// Paths no deterministic chain returns reach the connection through its random
// seeds only by the solver, which must accept them: the path a solve started on
// the walk's own faces returns when it is the walk itself (a vertex where the
// normals disagree, a sphere: nullopt, no seed converges to it, p = 0).
std::optional<RefractedPath> seed_reachable_solution(const Scene& scene, const Vec3& x, const Vec3& y,
                                                     const SpecularChain& walked, float lambda_nm);
// Whether max_seed_trials fresh seeds (reflecting too, as the excitation
// connection's) all miss `path`: SMS's capped count holds a path with weight
// 1 − (1 − p)^N, so the other strategy keeps it when this returns true.
bool seeds_miss(const Scene& scene, const Vec3& x, const Vec3& y, const RefractedPath& path, float lambda_nm, Rng& rng);

// Where a connection from `from` toward the direction `toward` starts: a medium
// point itself, a surface point offset off its surface to that side (the solves
// and legs cast plain rays from it; the other strategy's seeds must leave from it too).
Vec3 connection_start(const Scene& scene, const ShadowOrigin& from, const Vec3& toward);

// Π F_i of a solved path: Fresnel transmission at each face it crosses,
// reflectance where it mirrors, at the shading normals (also the probability
// that the path tracer's dielectrics choose those events).
float path_fresnel(const Scene& scene, const RefractedPath& path, float lambda_nm);
// dω_0/dA_y of a solved path: the solid angle at its start per unit area of the
// surface (normal n) at its end point, the generalised geometry term times |cos θ_y|.
double solid_angle_per_area(const RefractedPath& path, const Vec3& n);
// The paths the deterministic chains solve from x (a medium point) to the point
// z of a surface with geometric normal ng, no random seeds (the light a lit floor
// sends through a vessel's glass; integrator/bounce_connection.h), each with
// what it carries from z to x at the hero wavelength:
//   transport = Π F_i · T_legs · (n_x / n_z)² · dω_0/dA_z,
// dω_0/dA_z = dω_0/dA_⊥ · |cos θ_z| (solid angle at x per area at z).
// Blocked paths are left out.
struct PathToSurface {
  RefractedPath path;
  SampledSpectrum transport;
};
struct PathsToSurface {
  std::array<PathToSurface, DeterministicChains::kMax> paths;
  int count = 0;
};
PathsToSurface paths_to_surface_point(const Scene& scene, const Vec3& x, int medium, const Vec3& z, const Vec3& ng,
                                      PreparedMedia& media, Rng& rng);

// Light from one light reaching a point through the deterministic chains toward
// one light sample (area lights: a point uniform by area from `u`), plus the SMS
// estimate of one other solution:
// each path's direction at the point (first leg, toward the light) and what it
// brings, per lane of media.lambda(): radiance times solid angle,
//   L · Π F_i · T_media · (n_x / n_light)² · dω/dA_⊥ · |cos θ_light| / pdf_A,
// F_i = 1 − R_i where the path crosses, R_i where it reflects, or the delta
// lights' equivalents (R_i at the shading normal, as the path tracer scatters). A scattering point weights each path by its phase function
// or BSDF at wi; summed as they are, they are the fluence rate. The point is a
// medium point or a surface point (`from.hit`, offset off its surface toward
// the light). Paths through dispersive glass carry the hero wavelength only,
// standing for all lanes. The random seed runs with `seeds.probability`, its
// estimate divided by it, and may reflect if `seeds.reflect`. No path when
// blocked or none is found; nullopt for environment lights (the caller falls back).
struct SeedPolicy {
  float probability = 1.f;
  bool reflect = true;
  // Count the straight line's own path where it crosses no glass. Camera paths'
  // next-event estimation samples that one itself (MIS with BSDF sampling).
  bool clear_line = true;
};
struct ArrivingLight {
  struct Path {
    Vec3 wi;
    SampledSpectrum L;
    int faces = 0;  // dielectric faces on the way (0: the straight line through no glass)
    // For weighing against another strategy (excitation_connection.h): whether
    // a random seed found the path and, for area lights only, Π F_i at the
    // hero wavelength and the light point's area density per unit solid angle
    // at the point, pdf_A / (dω_0/dA_⊥ · |cos θ_light|) (0 for the others).
    float fresnel = 1.f;
    bool seeded = false;
    float pdf_solid_angle = 0.f;
  };
  std::array<Path, DeterministicChains::kMax + 1> paths;  // the deterministic chains' and a seed's
  int count = 0;
};
std::optional<ArrivingLight> light_through_dielectrics(const Scene& scene, const ShadowOrigin& from, int light_index,
                                                       Point2 u, PreparedMedia& media, Rng& rng, SeedPolicy seeds = {});
}  // namespace chlorovdb
