#pragma once
// Excitation connections through smooth dielectric surfaces: from a point in a
// medium to a point, spot, distant or area light through a chain of up to
// kMaxSpecularChain *parallel planar* dielectric faces (cuvette walls, a free
// surface), by solving for the refracted path exactly (Snell's invariant
// s = n_i sin θ_i, a 1-D monotone root) at the excitation wavelength.
//
// The chain is seeded by the straight line from the point to the light: the
// dielectric faces it crosses, in order. A connection is made only when they
// are all parallel planes (box faces, flat-shaded triangles); the refracted path
// through those planes is unique (the optical path length is strictly convex),
// and it counts only if it really crosses those faces and nothing else.
//
// Partition with `full` mode's continuation paths: a continuation from x that
// reaches an area light through dielectric transmissions only is dropped exactly
// when connection_owns() says the connection would have produced that path
// (same faces as the straight line's chain, all parallel). Everything else —
// curved or smooth-shaded glass, chains with a reflection, faces the straight
// line does not cross (near a vessel's edges) — stays with the continuation.
#include <array>
#include <optional>
#include <span>

#include "core/rng.h"
#include "integrator/transport.h"

namespace chlorovdb {

constexpr int kMaxSpecularChain = 4;

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
// A dielectric face crossed: the shape and its plane (geometric normal, offset
// dot(ng, p)). Two triangles of one flat quad are the same face.
struct ChainFace {
  int shape_id = -1, prim_id = -1;
  Vec3 ng;
  float offset = 0.f;
  Vec3 p;  // where the crossing ray met it
};
struct SpecularChain {
  std::array<ChainFace, kMaxSpecularChain> faces;
  int count = 0;
  bool planar_parallel = true;  // all faces flat-shaded planes with parallel normals
};
bool same_face(const ChainFace& a, const ChainFace& b);

// The dielectric faces crossed by the straight line from x toward y (or along
// y as a direction to infinity). nullopt when an opaque surface is crossed or
// more than kMaxSpecularChain dielectric faces are.
std::optional<SpecularChain> straight_line_chain(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity);

// A path a continuation walked from x (dielectric transmissions at `walked`,
// then the light at y): true when the connection strategy produces it.
bool connection_owns(const Scene& scene, const Vec3& x, const Vec3& y, const SpecularChain& walked);

// The solved refracted path: vertices on the chain's faces, leg directions
// (toward the light), Snell's cosines and the layers' relative indices.
struct RefractedPath {
  int count = 0;
  std::array<Vec3, kMaxSpecularChain> vertex;
  std::array<Vec3, kMaxSpecularChain + 1> dir;
  std::array<double, kMaxSpecularChain + 1> cos_theta, n;
  double solid_angle_per_area = 0;  // dω_0 / dA_⊥ at the end (finite end only)
};
// Through the chain's planes from x to the point y, or leaving toward the
// direction wi (to_infinity). Relative indices from the chain's dielectrics at
// `lambda_nm`. nullopt when the chain is not planar-parallel or no path exists.
std::optional<RefractedPath> solve_refracted_path(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                  const Vec3& y, bool to_infinity, float lambda_nm);

// Fluence-rate estimate at x (one wavelength: wl.count() == 1) from one light
// through the dielectric chain seeded by the straight line to one light sample
// (area lights: a point uniform by area from `u`):  L · Π(1 − R_i) · T_media ·
// (n_x / n_light)² · dω/dA_⊥ · |cos θ_light| / pdf_A, or the delta lights'
// equivalents. Zero when the path is blocked or the chain is not one it solves.
// Environment lights are not handled (returns nullopt: the caller falls back).
std::optional<float> connect_through_dielectrics(const Scene& scene, const Vec3& x, int medium, int light_index,
                                                 Point2 u, PreparedMedia& media, Rng& rng);

}  // namespace chlorovdb
