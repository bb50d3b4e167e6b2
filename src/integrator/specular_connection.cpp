#include "integrator/specular_connection.h"

#include <cmath>
#include <limits>

namespace chlorovdb {

namespace {

// Same tolerance GeometryScene uses for shadow rays: stop this fraction short of a target.
constexpr float kStopShort = 1e-4f;
// Normals this close are one plane orientation (cos of ~0.08°).
constexpr float kParallelCos = 1.f - 1e-6f;
// A walked vertex within this fraction of |y − x| of the solved one is the same path.
constexpr float kOwnedVertexTolerance = 1e-4f;

const Dielectric& dielectric_of(const Scene& scene, int shape_id) {
  return std::get<Dielectric>(scene.materials[scene.shapes[shape_id].material]);
}

// True when the ray from `ray.o` reaches face `f`'s shape at distance `dist`
// (its vertex) before any other surface that is not pass-through. On a smooth
// mesh a vertex on an edge may be reported on either triangle: the shape decides.
bool leg_reaches_face(const Scene& scene, Ray ray, float dist, const ChainFace& f) {
  const float slack = 1e-3f * dist + 1e-6f;
  float travelled = 0.f;
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, dist + slack - travelled);
    if (!hit) return false;
    const ShapeBinding& b = scene.shapes[hit->shape_id];
    if (!is_pass_through(scene, b)) {
      return hit->shape_id == f.shape_id && std::fabs(travelled + hit->t - dist) <= slack;
    }
    travelled += hit->t;
    ray = scene.geometry.spawn_ray(*hit, ray.d);
  }
  return false;
}

// Appends a face, keeping planar_parallel up to date.
void append_face(const Scene& scene, const ChainFace& f, SpecularChain* c) {
  if (f.reflect || !scene.geometry.flat_face(f.shape_id, f.prim_id)) c->planar_parallel = false;
  if (c->count > 0 && std::fabs(dot(f.ng, c->faces[0].ng)) < kParallelCos) c->planar_parallel = false;
  c->faces[c->count++] = f;
}
// Appends the hit's face to the chain; false when the surface is opaque (not a
// dielectric) or the chain is full.
bool append_dielectric_face(const Scene& scene, const SurfaceHit& hit, SpecularChain* c) {
  if (!scene.is_dielectric(scene.shapes[hit.shape_id]) || c->count == kMaxRefractedChain) return false;
  append_face(scene, ChainFace{hit.shape_id, hit.prim_id, hit.ng, dot(hit.ng, hit.p), hit.p}, c);
  return true;
}

// The chain's first j faces, as a chain of their own.
SpecularChain chain_prefix(const Scene& scene, const SpecularChain& chain, int j) {
  SpecularChain prefix;
  for (int i = 0; i < j; ++i) append_face(scene, chain.faces[i], &prefix);
  return prefix;
}

// Same shapes, events and every vertex within `tolerance`: one path (the
// vertices carry the float error of hits and scattered directions, ≈ 1e-6 of
// the path; distinct solutions through the same shapes lie far apart).
bool same_vertices(std::span<const ChainFace> a, std::span<const ChainFace> b, float tolerance) {
  if (a.size() != b.size()) return false;
  for (size_t j = 0; j < a.size(); ++j)
    if (a[j].shape_id != b[j].shape_id || a[j].reflect != b[j].reflect || length(a[j].p - b[j].p) > tolerance)
      return false;
  return true;
}

}  // namespace

SurfaceHit solved_vertex_hit(const ChainFace& f, const Vec3& ns) {
  SurfaceHit h;
  h.p = f.p;
  h.ng = f.ng;
  h.ns = ns;
  h.shape_id = f.shape_id;
  h.prim_id = f.prim_id;
  h.p_error = 64.f * 0x1p-24f * (max_component(abs(f.p)) + 1e-3f);  // on its triangle up to float rounding
  return h;
}

double planar_lateral_offset(std::span<const double> h, std::span<const double> n, double s) {
  double r = 0;
  for (size_t i = 0; i < h.size(); ++i)
    if (h[i] > 0) r += h[i] * s / std::sqrt(n[i] * n[i] - s * s);
  return r;
}

std::optional<double> solve_planar_invariant(std::span<const double> h, std::span<const double> n, double lateral) {
  // Every layer bounds s (a ray must exist in each, even one of zero thickness);
  // r(s) grows without bound only if a layer of the smallest index has thickness.
  double s_max = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < h.size(); ++i) s_max = std::min(s_max, n[i]);
  if (!(lateral > 0)) return 0.0;
  // Safeguarded Newton: r is increasing and convex, bracket [lo, hi] kept so a
  // step beyond it (the first one overshoots, by convexity) bisects instead.
  double lo = 0, hi = s_max, s = 0;
  for (int it = 0; it < 200; ++it) {
    double r = 0, dr = 0;
    for (size_t i = 0; i < h.size(); ++i) {
      if (h[i] == 0) continue;
      const double c2 = n[i] * n[i] - s * s;
      const double root = std::sqrt(c2);
      r += h[i] * s / root;
      dr += h[i] * n[i] * n[i] / (c2 * root);
    }
    const double f = r - lateral;
    if (std::fabs(f) <= 1e-13 * lateral) return s;
    if (f < 0) lo = s;
    else hi = s;
    double next = s - f / dr;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    // Converged to the float resolution of s (near grazing r' is huge, so |f|
    // cannot get below its rounding); a bracket closed on s_max means unreachable.
    if (hi - lo <= 1e-15 * s_max) return hi < s_max ? std::optional<double>(s) : std::nullopt;
    s = next;
  }
  return std::nullopt;
}

double planar_solid_angle_per_area(std::span<const double> h, std::span<const double> n, double s) {
  double q = 0, dr = 0;  // r/s and dr/ds
  for (size_t i = 0; i < h.size(); ++i) {
    if (h[i] == 0) continue;
    const double c2 = n[i] * n[i] - s * s;
    q += h[i] / std::sqrt(c2);
    dr += h[i] * n[i] * n[i] / (c2 * std::sqrt(c2));
  }
  const double n0 = n.front(), nk = n.back();
  const double cos0 = std::sqrt(std::max(0.0, 1 - s * s / (n0 * n0)));
  const double cosk = std::sqrt(std::max(0.0, 1 - s * s / (nk * nk)));
  return 1 / (n0 * n0 * q * dr * cos0 * cosk);
}

std::optional<SpecularChain> straight_line_chain(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity) {
  SpecularChain c;
  float t_max;
  Ray ray;
  if (to_infinity) {
    ray = Ray{x, normalize(y)};
    t_max = kInfinity;
  } else {
    const float dist = length(y - x);
    if (!(dist > 0.f)) return std::nullopt;
    ray = Ray{x, (y - x) / dist};
    t_max = dist * (1.f - kStopShort);
  }
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, t_max);
    if (!hit) return c;
    const ShapeBinding& b = scene.shapes[hit->shape_id];
    if (!is_pass_through(scene, b) && !append_dielectric_face(scene, *hit, &c)) return std::nullopt;
    ray = to_infinity ? scene.geometry.spawn_ray(*hit, ray.d) : scene.geometry.spawn_ray_to(*hit, y, &t_max);
  }
  return std::nullopt;
}

bool chain_enters(const SpecularChain& chain, int j, const Vec3& x) {
  const Vec3& from = j == 0 ? x : chain.faces[j - 1].p;
  return dot(chain.faces[j].p - from, chain.faces[j].ng) < 0.f;
}

std::array<double, kMaxSpecularChain + 1> chain_indices(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                        float lambda_nm) {
  std::array<double, kMaxSpecularChain + 1> n{};
  n[0] = 1;
  for (int j = 0; j < chain.count; ++j) {
    const float eta = ior_at(dielectric_of(scene, chain.faces[j].shape_id), lambda_nm);
    if (chain.faces[j].reflect) n[j + 1] = n[j];
    else n[j + 1] = n[j] * (chain_enters(chain, j, x) ? eta : 1.f / eta);  // entering: n_inside / n_outside
  }
  return n;
}

namespace {
// Bit j (0 < j < chain.count) is set when light leaving the chain's first j faces
// travels in the medium it leaves the whole chain in (the relative indices
// agree): that prefix can be a path to the light of its own.
unsigned exit_prefixes(const Scene& scene, const SpecularChain& chain, const Vec3& x, float lambda_nm) {
  const auto n = chain_indices(scene, chain, x, lambda_nm);
  unsigned prefixes = 0;
  for (int j = 1; j < chain.count; ++j)
    if (std::fabs(n[j] - n[chain.count]) <= 1e-6 * n[chain.count]) prefixes |= 1u << j;
  return prefixes;
}

// The walls of the vessel around x: along each world axis pointing to the light's
// side (dot(d, toward) > 0), the dielectric faces the ray from x crosses up to the
// first opaque surface, kept when they are flat and parallel and the first is a
// face of `vessel` (the shape the straight line leaves x through). A refracted
// path can leave through any wall: from under a cuvette's lid, a panel beside it
// shines in through the side wall the straight line crosses and, at grazing
// angles, through the lid and the front and back walls, whose paths start ≈ 40°
// off the straight line, outside the random seeds' cone. Each such chain solves
// in closed form.
int wall_chains(const Scene& scene, const Vec3& x, const Vec3& toward, int vessel, std::span<SpecularChain, 3> walls) {
  int count = 0;
  for (int axis = 0; axis < 3; ++axis)
    if (toward[axis] != 0.f) {
      Vec3 d(0.f);
      d[axis] = toward[axis] > 0.f ? 1.f : -1.f;
      SpecularChain c;
      Ray ray{x, d};
      bool full = false;
      for (int crossings = 0; crossings < 256; ++crossings) {
        const auto hit = scene.geometry.intersect(ray, kInfinity);
        if (!hit) break;
        const ShapeBinding& b = scene.shapes[hit->shape_id];
        if (!is_pass_through(scene, b)) {
          if (!scene.is_dielectric(b)) break;
          if (!append_dielectric_face(scene, *hit, &c) || !c.planar_parallel) {
            full = true;  // or curved: no wall
            break;
          }
        }
        ray = scene.geometry.spawn_ray(*hit, d);
      }
      if (!full && c.count > 0 && c.faces[0].shape_id == vessel) walls[size_t(count++)] = c;
    }
  return count;
}

// Chains mirrored in an outer face of x's vessel: along each world axis, away
// from the light, the flat faces of x's vessel (`straight`'s first face's shape)
// up to its outer face, which mirrors the path back through them, then the
// straight line's faces toward y. Light a cuvette's floor or lid mirrors by
// total internal reflection reaches the liquid near it this way. Kept only where
// the line toward y's mirror image y' would be totally reflected (n_x · sin θ > 1
// at the face, n_x the index at x relative to the light's side): the partial
// reflections, a few per cent, are the continuations'.
int mirror_chains(const Scene& scene, const Vec3& x, const Vec3& y, const SpecularChain& straight, double n_x,
                  float lambda_nm, std::span<SpecularChain, 3> mirrors) {
  int count = 0;
  const Vec3 toward = y - x;
  const double distance = length(toward);
  // y's mirror image in the plane of unit normal n at offset `plane`.
  const auto image_of_y = [&y](const Vec3& n, float plane) { return y - n * (2.f * (dot(n, y) - plane)); };
  for (int axis = 0; axis < 3; ++axis) {
    if (toward[axis] == 0.f) continue;
    // The line toward the image is steepest to the face when the face passes
    // through x (then it is the line toward y): no face across the axis farther
    // away can reflect it totally.
    const double cos_line = toward[axis] / distance;
    if (!(n_x * n_x * (1.0 - cos_line * cos_line) > 1.0)) continue;
    Vec3 d(0.f);
    d[axis] = toward[axis] > 0.f ? -1.f : 1.f;
    // The faces the walk along d crosses (at most two, flat): the last is the mirror.
    std::array<ChainFace, 2> along;
    int k = 0;
    Ray ray{x, d};
    for (int crossings = 0; crossings < 256; ++crossings) {
      const auto hit = scene.geometry.intersect(ray, kInfinity);
      if (!hit) break;
      const ShapeBinding& b = scene.shapes[hit->shape_id];
      if (!is_pass_through(scene, b)) {
        if (!scene.is_dielectric(b) || !scene.geometry.flat_face(hit->shape_id, hit->prim_id) || k == 2) break;
        along[size_t(k++)] = ChainFace{hit->shape_id, hit->prim_id, hit->ng, dot(hit->ng, hit->p), hit->p};
      }
      ray = scene.geometry.spawn_ray(*hit, d);
    }
    if (k == 0 || along[0].shape_id != straight.faces[0].shape_id || k + (k - 1) + straight.count > kMaxSpecularChain)
      continue;
    const Vec3 n = normalize(along[size_t(k - 1)].ng);
    const float plane = dot(n, along[size_t(k - 1)].p);
    const Vec3 down = normalize(image_of_y(n, plane) - x);
    if (!(n_x * n_x * (1.0 - double(dot(down, n)) * dot(down, n)) > 1.0)) continue;
    // The chain by its faces, not by where a straight line meets them (refraction
    // in a thin wall moves the path off the unrefracted line's faces): those to
    // the mirror, the mirror, those back, then the straight line's toward y. The
    // first guesses treat the wall as thin: the path mirrored at the first face's
    // plane (point m), its vertices in the wall spread along the wall by the
    // thickness times tan θ inside it, those toward y where the line from m meets them.
    const auto meet = [](const Vec3& o, const Vec3& dir, const ChainFace& f, Vec3* p) {
      const float along_normal = dot(f.ng, dir);
      if (along_normal == 0.f) return false;
      const float t = (f.offset - dot(f.ng, o)) / along_normal;
      *p = o + dir * t;
      return t > 0.f;
    };
    const ChainFace& inner = along[0];
    const Vec3 n0 = normalize(inner.ng);
    const float plane0 = dot(n0, inner.p);
    const Vec3 toward_inner_image = normalize(image_of_y(n0, plane0) - x);
    Vec3 m;
    if (!meet(x, toward_inner_image, inner, &m)) continue;
    Vec3 lateral = toward_inner_image - n0 * dot(toward_inner_image, n0);
    const float sin_x = length(lateral);
    lateral = sin_x > 0.f ? lateral / sin_x : Vec3(0.f);
    SpecularChain first;
    append_face(scene, inner, &first);
    const double sin_wall = sin_x / chain_indices(scene, first, x, lambda_nm)[1];  // Snell into the wall
    const float shift = k > 1 && sin_wall < 1.0 ? std::fabs(plane - dot(n, inner.p)) *
                                                      float(sin_wall / std::sqrt(1.0 - sin_wall * sin_wall))
                                                : 0.f;
    SpecularChain c;
    for (int j = 0; j < k; ++j) {
      ChainFace f = along[size_t(j)];
      f.p = m - lateral * (j == 0 ? shift : 0.f) +
            normalize(f.ng) * (dot(normalize(f.ng), f.p) - dot(normalize(f.ng), m));
      f.reflect = j == k - 1;
      append_face(scene, f, &c);
    }
    for (int j = k - 2; j >= 0; --j) {
      ChainFace f = along[size_t(j)];
      f.p = m + lateral * shift;
      append_face(scene, f, &c);
    }
    const Vec3 from = m + lateral * shift;
    const Vec3 up = normalize(y - from);
    bool ok = true;
    for (int j = 0; j < straight.count && ok; ++j) {
      ChainFace f = straight.faces[size_t(j)];
      ok = meet(from, up, f, &f.p);
      append_face(scene, f, &c);
    }
    if (ok) mirrors[size_t(count++)] = c;
  }
  return count;
}

// deterministic_chains, or only its chains with a mirror vertex (`mirrored`) or
// only those without: a walk matches only chains of its own kind.
enum class ChainKinds { all, unmirrored, mirrored };
DeterministicChains chains_of_kind(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity, bool area_light,
                                   float lambda_nm, ChainKinds kinds) {
  DeterministicChains out;
  const auto chain = straight_line_chain(scene, x, y, to_infinity);
  if (!chain) return out;
  if (kinds != ChainKinds::mirrored) out.chains[size_t(out.count++)] = *chain;
  if (chain->count == 0) return out;
  // A vessel whose first face is curved (a beaker's, a teapot's smooth-shaded
  // mesh) has no walls: the axes' walks would find none (one run each read 14 %
  // and 17 % more CPU time with them on glass_UVB_5uM_Q0.23 and the teapot).
  const int vessel = chain->faces[0].shape_id;
  const bool flat = scene.geometry.flat_face(vessel, chain->faces[0].prim_id);
  const auto add_mirrors = [&] {
    if (to_infinity || !flat) return;
    std::array<SpecularChain, 3> mirrors;
    // x's index relative to the light's side (chain_indices are relative to x's).
    const double n_x = 1.0 / chain_indices(scene, *chain, x, lambda_nm)[size_t(chain->count)];
    const int m = mirror_chains(scene, x, y, *chain, n_x, lambda_nm, mirrors);
    for (int i = 0; i < m; ++i) out.chains[size_t(out.count++)] = mirrors[size_t(i)];
  };
  if (kinds == ChainKinds::mirrored) {
    add_mirrors();
    return out;
  }
  if (area_light && chain->count > 1) {
    const unsigned prefixes = exit_prefixes(scene, *chain, x, lambda_nm);
    for (int j = 1; j < chain->count; ++j)
      if (prefixes >> j & 1u) out.chains[size_t(out.count++)] = chain_prefix(scene, *chain, j);
  }
  if (!flat) return out;
  std::array<SpecularChain, 3> walls;
  const int n = wall_chains(scene, x, to_infinity ? y : y - x, vessel, walls);
  for (int i = 0; i < n; ++i) out.chains[size_t(out.count++)] = walls[size_t(i)];
  if (kinds == ChainKinds::all) add_mirrors();
  return out;
}

}  // namespace

DeterministicChains deterministic_chains(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity,
                                         bool area_light, float lambda_nm) {
  return chains_of_kind(scene, x, y, to_infinity, area_light, lambda_nm, ChainKinds::all);
}

std::optional<RefractedPath> deterministic_solution(const Scene& scene, const Vec3& x, const Vec3& y,
                                                    const SpecularChain& walked, float lambda_nm) {
  bool mirrored = false;
  for (int j = 0; j < walked.count; ++j) mirrored |= walked.faces[size_t(j)].reflect;
  const DeterministicChains candidates =
      chains_of_kind(scene, x, y, false, true, lambda_nm, mirrored ? ChainKinds::mirrored : ChainKinds::unmirrored);
  const float tolerance = kOwnedVertexTolerance * length(y - x);
  for (int i = 0; i < candidates.count; ++i) {
    const SpecularChain& c = candidates.chains[size_t(i)];
    if (c.count != walked.count) continue;
    const auto path = solve_refracted_path(scene, c, x, y, false, lambda_nm);
    if (path &&
        same_vertices({path->face.data(), size_t(path->count)}, {walked.faces.data(), size_t(walked.count)}, tolerance))
      return path;
  }
  return std::nullopt;
}

bool solved_deterministically(const Scene& scene, const Vec3& x, const Vec3& y, const SpecularChain& walked,
                              float lambda_nm) {
  if (walked.count == 0) return false;  // straight to the light: the first-segment rule owns it
  return deterministic_solution(scene, x, y, walked, lambda_nm).has_value();
}

std::optional<RefractedPath> solve_refracted_path(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                  const Vec3& y, bool to_infinity, float lambda_nm) {
  if (!chain.planar_parallel) return solve_manifold_path(scene, chain, x, y, to_infinity, lambda_nm);
  const int k = chain.count;
  const Vec3 toward = to_infinity ? y : y - x;
  Vec3 N = k > 0 ? chain.faces[0].ng : normalize(toward);
  if (dot(N, toward) < 0.f) N = -N;
  RefractedPath P;
  P.count = k;
  P.n = chain_indices(scene, chain, x, lambda_nm);
  std::array<double, kMaxSpecularChain + 1> h{};
  double z_prev = dot(N, x);
  for (int j = 0; j < k; ++j) {
    const double c = dot(N, chain.faces[j].p);
    h[j] = std::max(0.0, c - z_prev);
    z_prev = c;
  }
  const std::span<const double> hs(h.data(), k + 1), ns(P.n.data(), k + 1);
  Vec3 lateral = toward - N * dot(toward, N);
  const float lateral_len = length(lateral);
  const Vec3 e = lateral_len > 0.f ? lateral / lateral_len : Vec3(0.f);
  double s;
  if (to_infinity) {
    s = P.n[k] * std::min(1.0, double(lateral_len) / double(length(toward)));
    for (int i = 0; i <= k; ++i)
      if (!(s < P.n[i])) return std::nullopt;  // total internal reflection on the way in
  } else {
    h[k] = std::max(0.0, double(dot(N, y)) - z_prev);
    const auto solved = solve_planar_invariant(hs, ns, lateral_len);
    if (!solved) return std::nullopt;
    s = *solved;
    P.geometry = planar_solid_angle_per_area(hs, ns, s);
  }
  std::array<double, kMaxSpecularChain + 1> cos_theta{};
  double H = 0, R = 0;
  for (int i = 0; i <= k; ++i) {
    const double sin_i = s / P.n[i];
    cos_theta[i] = std::sqrt(std::max(0.0, 1 - sin_i * sin_i));
    P.dir[i] = normalize(N * float(cos_theta[i]) + e * float(sin_i));
    if (i == k) break;
    H += h[i];
    R += h[i] * sin_i / cos_theta[i];
    P.face[i] = chain.faces[i];
    P.face[i].p = x + N * float(H) + e * float(R);
    P.ns[i] = chain.faces[i].ng;
  }
  // A collimated beam's cross-section changes by cos θ_last / cos θ_0 (power conservation at every plane).
  if (to_infinity) P.geometry = cos_theta[k] / cos_theta[0];
  return P;
}

namespace {
// A walked seed whose last leg leaves more than 60° away from the light rarely
// converges: on the teapot's spot lights 97 % of such solves failed, and they
// were 63 % of all failed solves. Refusing them changes each solution's seed
// probability p(S) alike for the first find and the geometric re-finds, so the
// estimate stays unbiased; solutions reached from nearer seeds only get rarer.
constexpr float kSeedAimCos = 0.5f;
bool aims_at(const Vec3& d, const Vec3& toward) { return dot(d, toward) >= kSeedAimCos * length(toward); }
}  // namespace

std::optional<SpecularChain> specular_seed_chain(const Scene& scene, const Vec3& x, const Vec3& d, const Vec3& y,
                                                 bool to_infinity, float lambda_nm, bool reflect_too, Rng& rng) {
  SpecularChain c;
  Ray ray{x, d};
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, kInfinity);
    if (!to_infinity) {
      // A light on a surface (stopped short of, as shadow rays are) passes too.
      const float t_y = dot(y - ray.o, ray.d);
      if (t_y > 0.f && (!hit || t_y * (1.f - kStopShort) < hit->t))
        return c.count > 0 && aims_at(ray.d, y - ray.o) ? std::optional(c) : std::nullopt;
    }
    if (!hit) return to_infinity && c.count > 0 && aims_at(ray.d, y) ? std::optional(c) : std::nullopt;
    const ShapeBinding& b = scene.shapes[hit->shape_id];
    if (is_pass_through(scene, b)) {
      ray = scene.geometry.spawn_ray(*hit, ray.d);
      continue;
    }
    if (!scene.is_dielectric(b) || c.count == kMaxRefractedChain) return std::nullopt;
    // As the glass scatters: reflected with probability R (1 under total internal reflection).
    const Vec3 wo = -ray.d;
    const float eta = ior_at(dielectric_of(scene, hit->shape_id), lambda_nm);
    const bool reflect = reflect_too && rng.uniform() < fresnel_dielectric(dot(wo, hit->ns), eta);
    Vec3 wi;
    float eta_crossed;
    if (reflect) wi = hit->ns * (2.f * dot(wo, hit->ns)) - wo;
    else if (!refract(wo, hit->ns, eta, &wi, &eta_crossed)) return std::nullopt;
    append_face(scene, ChainFace{hit->shape_id, hit->prim_id, hit->ng, dot(hit->ng, hit->p), hit->p, reflect}, &c);
    ray = scene.geometry.spawn_ray(*hit, wi);
  }
  return std::nullopt;
}

namespace {

// Where the connection ends: a point on the light (y, its normal and the
// sampling density by area) or, for a distant light, the direction toward it.
struct LightEnd {
  Vec3 y, n;
  float pdf_area = 1.f;
  bool to_infinity = false;
};

// Fresnel transmission at face j of the path (reflectance at a mirror vertex),
// at the shading normal as the path tracer's dielectric scatters.
float face_fresnel(const Scene& scene, const RefractedPath& path, int j, float lambda_nm) {
  const float R =
      fresnel_dielectric(dot(-path.dir[j], path.ns[j]), ior_at(dielectric_of(scene, path.face[j].shape_id), lambda_nm));
  return path.face[j].reflect ? R : 1.f - R;
}

// What one solved path from x to `end` lets through, per lane of media.lambda():
// face_fresnel at every face and the medium transmittance on every leg, each
// leg reaching its face and nothing else. Zero when blocked.
// The path and its Fresnel factors are the hero wavelength's; the caller keeps
// only the hero lane when the glass disperses.
SampledSpectrum path_transmission(const Scene& scene, const Vec3& x, int medium, const LightEnd& end,
                                  const RefractedPath& path, PreparedMedia& media, Rng& rng) {
  const SampledWavelengths& wl = media.lambda();
  const int k = path.count;
  // Medium transmittance of one leg: the shared light connection, stopped by any glass.
  const auto leg_transmittance = [&](const ShadowOrigin& from, const LightTarget& to) {
    return connect_to_light(scene, from, to, media, rng, ConnectionOptions{}).T;
  };
  // Only the lanes the path carries decide whether it is blocked.
  const auto dark = [&](const SampledSpectrum& w) {
    for (int i = 0; i < wl.count(); ++i)
      if (w[i] != 0.f) return false;
    return true;
  };
  SampledSpectrum weight(1.f);
  int leg_medium = medium;
  SurfaceHit prev;
  for (int j = 0; j < k; ++j) {
    const ChainFace& f = path.face[j];
    const Vec3& v = f.p;
    const Vec3& d = path.dir[j];
    const Ray ray = j == 0 ? Ray{x, d} : scene.geometry.spawn_ray(prev, d);
    if (!leg_reaches_face(scene, ray, length(v - ray.o), f)) return {};
    const SurfaceHit here = solved_vertex_hit(f, path.ns[j]);
    const ShapeBinding& b = scene.shapes[f.shape_id];
    // The first leg is traced from the face back to x: spawn_ray_to stops short
    // of its target, and a medium point has no surface to stop short of. It
    // starts in the medium on x's side of the face, which differs from x's own
    // when an interface (a medium boundary) lies between them.
    weight *= j == 0 ? leg_transmittance(ShadowOrigin{v, medium_after_crossing(b, f.ng, -d), &here}, LightTarget{-d, x})
                     : leg_transmittance(ShadowOrigin{prev.p, leg_medium, &prev}, LightTarget{d, v});
    weight *= face_fresnel(scene, path, j, wl[0]);
    if (dark(weight)) return {};
    leg_medium = medium_after_crossing(b, f.ng, path.dir[j + 1]);  // where the next leg runs
    prev = here;
  }
  const Vec3& d_last = path.dir[k];
  const ShadowOrigin from = k == 0 ? ShadowOrigin{x, medium, nullptr} : ShadowOrigin{prev.p, leg_medium, &prev};
  weight *= leg_transmittance(from, LightTarget{d_last, end.to_infinity ? prev.p + d_last * kInfinity : end.y,
                                                end.to_infinity});
  if (dark(weight)) return {};
  return weight;
}

// dω_0/dA_⊥ with the radiance compressed into the denser medium at x:
// (n_x / n_end)², n_x = 1 in the path's relative indices.
double compressed_geometry(const RefractedPath& path) {
  return path.geometry / (path.n[path.count] * path.n[path.count]);
}

// Light arriving at x from `light` along one solved path, per lane of
// media.lambda(): radiance times solid angle (the fluence rate it brings), with
// path_transmission and the generalised geometry term. Zero when blocked.
SampledSpectrum refracted_path_light(const Scene& scene, const Vec3& x, int medium, const Light& light,
                                     const LightEnd& end, const RefractedPath& path, PreparedMedia& media, Rng& rng) {
  const SampledWavelengths& wl = media.lambda();
  const SampledSpectrum weight = path_transmission(scene, x, medium, end, path, media, rng);
  if (weight.is_black()) return {};
  const Vec3& d_last = path.dir[path.count];
  if (end.to_infinity) {
    const auto& distant = std::get<DistantLight>(light);
    return distant.L.sample(wl) * (distant.scale * float(path.geometry)) * weight;
  }
  const float g = float(compressed_geometry(path));
  if (const auto* area = std::get_if<AreaLight>(&light))
    return Le_area(*area, end.n, -d_last, wl) * (g * std::fabs(dot(end.n, d_last)) / end.pdf_area) * weight;
  if (const auto* point = std::get_if<PointLight>(&light)) return point->I.sample(wl) * (point->scale * g) * weight;
  const auto& spot = std::get<SpotLight>(light);
  return spot.I.sample(wl) * (spot.scale * spot_falloff(spot, -d_last) * g) * weight;
}

// SMS seed direction, from a mixture: half the seeds uniform in the cone of
// half-angle 30° around the straight line to the light (where the solutions a
// straight line misses through curved glass mostly start: measured on the
// teapot's spot lights, this half keeps the estimate's variance near the
// straight-line solve's), half toward a point uniform by area on one of the
// scene's dielectric shapes (there is one at least) picked uniformly (solutions
// far off the line, a lens beside it).
std::optional<Vec3> sample_seed_direction(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity, Rng& rng) {
  constexpr float kConeCos = 0.8660254f;  // cos 30°
  if (rng.uniform() < 0.5f) {
    const Vec3 axis = normalize(to_infinity ? y : y - x);
    return Frame::from_z(axis).to_world(sample_uniform_cone(Point2{rng.uniform(), rng.uniform()}, kConeCos));
  }
  const int dielectrics = int(scene.dielectric_shapes.size());
  const int pick = std::min(int(rng.uniform() * float(dielectrics)), dielectrics - 1);
  const Point2 u{rng.uniform(), rng.uniform()};
  const Vec3 d = scene.geometry.sample_area(scene.dielectric_shapes[size_t(pick)], u).p - x;
  const float len = length(d);
  return len > 0.f ? std::optional(d / len) : std::nullopt;
}

std::optional<RefractedPath> solve_from_seed(const Scene& scene, const Vec3& x, const Vec3& y,
                                             bool to_infinity, float lambda_nm, bool reflect_too, Rng& rng) {
  const auto d = sample_seed_direction(scene, x, y, to_infinity, rng);
  if (!d) return std::nullopt;
  const auto chain = specular_seed_chain(scene, x, *d, y, to_infinity, lambda_nm, reflect_too, rng);
  if (!chain) return std::nullopt;
  return solve_refracted_path(scene, *chain, x, y, to_infinity, lambda_nm);
}

// The vertex tolerance for telling a path to `end` from x apart from another:
// a fraction of the distance to the light point (distant lights: to the path's
// last vertex; a path through no glass is never compared).
float path_tolerance(const RefractedPath& path, const Vec3& x, const LightEnd& end) {
  if (!end.to_infinity) return kOwnedVertexTolerance * length(end.y - x);
  return path.count > 0 ? kOwnedVertexTolerance * length(path.face[path.count - 1].p - x) : 0.f;
}

bool same_path(const RefractedPath& a, const RefractedPath& b, float tolerance) {
  return same_vertices({a.face.data(), size_t(a.count)}, {b.face.data(), size_t(b.count)}, tolerance);
}

// Random seeds drawn per other solution S before SMS's count gives up. Delta
// lights have no other strategy: the cap scales a solution's estimate by
// 1 − (1 − p)^cap, a bias only where p < 1/cap. Area lights give continuations
// the rest (seeds_miss), exact for any cap that depends on S alone, so a
// path with a mirror vertex gets a low one: seeds that reflect find many rare
// solutions (a beaker's curved wall mirrors the lamp from every triangle), and
// on glass_UVB_5uM_Q0.23 a cap of 1024 for them took 1.3× the CPU time of 64 at
// the same fluorescence error (relMSE 0.106 and 0.105 at 512 spp, 6 seeds).
// Crossings only keep 1024: the seeds find paths through glass beside the
// straight line with p of a few per cent (a cuvette's lid, which the walls also
// solve: ≈ 2 %), and left to continuations (27 % of the time with a cap of 64)
// they are the tail.
int max_seed_trials(bool area_light, std::span<const ChainFace> faces) {
  constexpr int kMaxSeedTrials = 1024, kMaxMirroredSeedTrials = 64;
  if (!area_light) return kMaxSeedTrials;
  for (const ChainFace& f : faces)
    if (f.reflect) return kMaxMirroredSeedTrials;
  return kMaxSeedTrials;
}

// The deterministic solves (deterministic_chains) from x toward `end`: the
// straight line's chain (its clear path through no glass if `clear_line`), for
// area lights (and surface points) its prefixes, and the walls around x; a path
// two of them return counts once.
struct SolvedPaths {
  std::array<RefractedPath, DeterministicChains::kMax> paths;
  int count = 0;
};
SolvedPaths solve_deterministic_chains(const Scene& scene, const Vec3& x, const LightEnd& end, bool area_light,
                                       bool clear_line, float lambda_nm) {
  SolvedPaths solved;
  const DeterministicChains candidates = deterministic_chains(scene, x, end.y, end.to_infinity, area_light, lambda_nm);
  for (int i = 0; i < candidates.count; ++i) {
    const SpecularChain& c = candidates.chains[size_t(i)];
    if (c.count == 0 && !clear_line) continue;
    const auto path = solve_refracted_path(scene, c, x, end.y, end.to_infinity, lambda_nm);
    if (!path) continue;
    const float tolerance = path_tolerance(*path, x, end);
    bool known = false;
    for (int j = 0; j < solved.count; ++j) known |= same_path(*path, solved.paths[size_t(j)], tolerance);
    if (!known) solved.paths[size_t(solved.count++)] = *path;
  }
  return solved;
}

}  // namespace

std::optional<RefractedPath> solve_from_random_seed(const Scene& scene, const Vec3& x, const Vec3& y, bool to_infinity,
                                                    float lambda_nm, bool reflect_too, Rng& rng) {
  if (scene.dielectric_shapes.empty()) return std::nullopt;
  return solve_from_seed(scene, x, y, to_infinity, lambda_nm, reflect_too, rng);
}

std::optional<RefractedPath> seed_reachable_solution(const Scene& scene, const Vec3& x, const Vec3& y,
                                                     const SpecularChain& walked, float lambda_nm) {
  if (walked.count == 0 || walked.count > kMaxRefractedChain || scene.dielectric_shapes.empty()) return std::nullopt;
  SpecularChain own;
  for (int j = 0; j < walked.count; ++j) append_face(scene, walked.faces[j], &own);
  auto path = solve_refracted_path(scene, own, x, y, false, lambda_nm);
  const float tolerance = kOwnedVertexTolerance * length(y - x);
  if (!path ||
      !same_vertices({path->face.data(), size_t(path->count)}, {walked.faces.data(), size_t(walked.count)}, tolerance))
    return std::nullopt;
  return path;
}

bool seeds_miss(const Scene& scene, const Vec3& x, const Vec3& y, const RefractedPath& path, float lambda_nm,
                Rng& rng) {
  const float tolerance = kOwnedVertexTolerance * length(y - x);
  const int max_trials = max_seed_trials(true, {path.face.data(), size_t(path.count)});
  for (int trial = 0; trial < max_trials; ++trial) {
    const auto found = solve_from_seed(scene, x, y, false, lambda_nm, true, rng);
    if (found && same_path(*found, path, tolerance)) return false;
  }
  return true;
}

Vec3 connection_start(const Scene& scene, const ShadowOrigin& from, const Vec3& toward) {
  return from.hit ? scene.geometry.spawn_ray(*from.hit, toward).o : from.p;
}

float path_fresnel(const Scene& scene, const RefractedPath& path, float lambda_nm) {
  float F = 1.f;
  for (int j = 0; j < path.count; ++j) F *= face_fresnel(scene, path, j, lambda_nm);
  return F;
}

double solid_angle_per_area(const RefractedPath& path, const Vec3& n) {
  return path.geometry * std::fabs(dot(n, path.dir[path.count]));
}

PathsToSurface paths_to_surface_point(const Scene& scene, const Vec3& x, int medium, const Vec3& z, const Vec3& ng,
                                      PreparedMedia& media, Rng& rng) {
  LightEnd end;
  end.y = z, end.n = ng;
  const SolvedPaths solved = solve_deterministic_chains(scene, x, end, true, true, media.lambda()[0]);
  PathsToSurface out;
  for (int i = 0; i < solved.count; ++i) {
    const RefractedPath& path = solved.paths[i];
    PathToSurface& p = out.paths[size_t(out.count)];
    p.transport = path_transmission(scene, x, medium, end, path, media, rng);
    if (p.transport.is_black()) continue;
    p.path = path;
    p.transport *= float(compressed_geometry(path) * std::fabs(dot(ng, path.dir[path.count])));
    ++out.count;
  }
  return out;
}

std::optional<ArrivingLight> light_through_dielectrics(const Scene& scene, const ShadowOrigin& from, int light_index,
                                                       Point2 u, PreparedMedia& media, Rng& rng,
                                                       SeedPolicy seeds) {
  const Light& light = scene.lights[light_index];
  if (std::holds_alternative<EnvironmentLight>(light)) return std::nullopt;
  const SampledWavelengths& wl = media.lambda();
  const float lambda_nm = wl[0];
  LightEnd end;
  end.to_infinity = std::holds_alternative<DistantLight>(light);
  if (const auto* area = std::get_if<AreaLight>(&light)) {
    const ShapeSample ss = scene.geometry.sample_area(area->shape_id, u);
    end.y = ss.p, end.n = ss.n, end.pdf_area = ss.pdf_area;
  } else if (const auto position = light_position(light)) {
    end.y = *position;
  } else {
    end.y = -std::get<DistantLight>(light).direction;  // toward the light
  }
  const Vec3 x = connection_start(scene, from, end.to_infinity ? end.y : end.y - from.p);
  const int medium = from.medium;

  ArrivingLight arriving;
  bool dispersed = false;  // a path crossed dispersive glass: only its hero wavelength is right
  const bool area_light = std::holds_alternative<AreaLight>(light);
  const auto add = [&](const RefractedPath& path, const SampledSpectrum& L, float count, bool seeded) {
    if (L.is_black()) return;
    ArrivingLight::Path& p = arriving.paths[arriving.count++];
    p.wi = path.dir[0];
    p.faces = path.count;
    p.L = L * count;
    p.seeded = seeded;
    if (area_light) {  // what only a strategy sharing area lights' paths reads
      p.fresnel = path_fresnel(scene, path, lambda_nm);
      p.pdf_solid_angle = float(end.pdf_area / solid_angle_per_area(path, end.n));
    }
    for (int j = 0; j < path.count; ++j) dispersed |= is_dispersive(dielectric_of(scene, path.face[j].shape_id));
  };
  const SolvedPaths solved = solve_deterministic_chains(scene, x, end, area_light, seeds.clear_line, lambda_nm);
  for (int i = 0; i < solved.count; ++i)
    add(solved.paths[i], refracted_path_light(scene, x, medium, light, end, solved.paths[i], media, rng), 1.f, false);

  // The other solutions by SMS's unbiased estimate (Zeltner et al. 2020, §4.3),
  // for every light: a point inside a cuvette under a side lamp is also reached
  // through the lid, at a grazing angle, where the straight line crosses the
  // side wall. A random seed converges to a solution S with some probability
  // p(S); the number of seeds drawn until one converges to S again is geometric
  // with mean 1/p(S), so f(S) times that count estimates f(S)/p(S) and the sum
  // over S is unbiased. The deterministic solutions are counted above, so a seed
  // that returns one adds nothing. The count is capped (max_seed_trials); the
  // expected work is one seed plus one geometric run per other solution,
  // whatever the p.
  if (!scene.dielectric_shapes.empty() && (seeds.probability >= 1.f || rng.uniform() < seeds.probability)) {
    const auto seed = [&] {
      return solve_from_seed(scene, x, end.y, end.to_infinity, lambda_nm, seeds.reflect, rng);
    };
    const auto found = seed();
    const float tolerance = found ? path_tolerance(*found, x, end) : 0.f;
    bool known = false;
    for (int i = 0; found && i < solved.count; ++i) known |= same_path(*found, solved.paths[i], tolerance);
    if (found && !known) {
      const SampledSpectrum L = refracted_path_light(scene, x, medium, light, end, *found, media, rng);
      if (!L.is_black()) {
        const int max_trials =
            max_seed_trials(area_light, {found->face.data(), size_t(found->count)});
        int trials = 1;
        for (; trials < max_trials; ++trials) {
          const auto again = seed();
          if (again && same_path(*again, *found, tolerance)) break;
        }
        add(*found, L, float(trials) / std::min(1.f, seeds.probability), true);
      }
    }
  }
  // Dispersive glass bends each wavelength its own way: the paths above are the
  // hero's, so the other lanes are dropped and the hero stands for all of them
  // (as SampledWavelengths::terminate_secondary, for this estimate only).
  if (dispersed && wl.count() > 1) {
    const float hero_share = wl.secondary_terminated() ? 1.f : float(wl.count());
    for (int i = 0; i < arriving.count; ++i) {
      SampledSpectrum hero;
      hero[0] = arriving.paths[i].L[0] * hero_share;
      arriving.paths[i].L = hero;
    }
  }
  return arriving;
}

}  // namespace chlorovdb
