// Manifold next-event estimation through chains of smooth dielectric mesh faces
// (solve_manifold_path, declared in specular_connection.h).
//
// Unknowns: the k vertices x_1..x_k, each moved in the plane of its triangle by
// barycentric offsets (b1, b2); the end points x_0 (the event point) and x_{k+1}
// (the light point, or a direction to infinity) are fixed. Constraint per
// vertex (Hanika et al. 2015): the generalised half vector h = η_a w_a + η_b w_b
// (unit directions to the previous and the next vertex, indices on their sides)
// is parallel to the shading normal n — Snell's law with the refracted
// directions on opposite sides — written as its two tangential components
// c = (h·s, h·t). Not normalising h keeps the constraint regular for
// index-matched glass, where h vanishes at the solution.
//
// Newton steps on the 2k × 2k constraint Jacobian (block tridiagonal: c_j
// depends on x_{j-1}, x_j, x_{j+1} only), each followed by re-projection onto
// the mesh: the chain is re-walked from x_0, every vertex re-intersected by the
// ray from its (re-projected) predecessor toward its proposed position, so a
// vertex can move onto a neighbouring triangle of the same shape. The step is
// halved while it fails to lower the residual (SMS's step control).
//
// The generalised geometry term comes from the same Jacobian by the implicit
// function theorem: moving the end point by δy changes the vertices by
// δU = −J⁻¹ ∂c/∂y δy, which moves the start direction ω_0. Any smooth choice of
// the tangent frames (s, t) gives the same δU at a solution (it multiplies each
// block row by a rotation), so the frame's own derivative is dropped from J:
// its term is proportional to the constraint and vanishes at a solution, and
// Newton keeps its quadratic convergence.
#include <cmath>

#include "integrator/specular_connection.h"

namespace chlorovdb {

namespace {

struct Vec3d {
  double x = 0, y = 0, z = 0;
};
Vec3d to_double(const Vec3& v) { return {v.x, v.y, v.z}; }
Vec3 to_float(const Vec3d& v) { return {float(v.x), float(v.y), float(v.z)}; }
Vec3d operator+(const Vec3d& a, const Vec3d& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3d operator-(const Vec3d& a, const Vec3d& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3d operator*(const Vec3d& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
Vec3d operator*(double s, const Vec3d& a) { return a * s; }
double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double length(const Vec3d& a) { return std::sqrt(dot(a, a)); }

// Two unit tangents completing n (Duff et al. 2017).
void tangent_frame(const Vec3d& n, Vec3d* s, Vec3d* t) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1 / (sign + n.z), b = n.x * n.y * a;
  *s = {1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
  *t = {b, sign + n.y * n.y * a, -n.y};
}

constexpr int kMaxUnknowns = 2 * kMaxSpecularChain;
constexpr int kMaxNewtonSteps = 12;  // converging solves take ~3-6; the rest rarely recover
// From the third step on, a step that lowers the residual by less than this
// factor ends the solve: a chain with no solution creeps toward a residual
// minimum above zero, while converging solves are quadratic by then. On
// glass_UVB_5uM_Q0.23 failing solves took 64 % of the re-projections; stopping
// them so took 13 % off its render time (the teapot's 15 %) and gave up 0.8 %
// of the solutions (docs/fluorescence.md).
constexpr double kStagnationFactor = 0.9;
constexpr int kFirstStagnationCheck = 3;
// Converged when every |h_tangential| / (η_a + η_b) (the sine of the angle
// error, roughly) is below this; quadratic convergence usually ends far below.
constexpr double kConstraintTolerance = 1e-7;

// A chain vertex on the plane of its triangle: x(b1, b2) = p0 + b1 e1 + b2 e2,
// unnormalised shading normal N = n0 + b1 dn1 + b2 dn2 (a hit's interpolation).
struct ManifoldVertex {
  int shape_id = -1, prim_id = -1;
  Vec3d p0, e1, e2, n0, dn1, dn2, ng;
  double b1 = 0, b2 = 0;
  Vec3d x;
  // At x: the shading normal turned to ng's side and its derivatives in b1, b2.
  Vec3d n, dn_db1, dn_db2;
};

bool set_patch(const GeometryScene& geometry, int shape_id, int prim_id, ManifoldVertex* v) {
  const auto patch = geometry.surface_patch(shape_id, prim_id);
  if (!patch) return false;
  v->shape_id = shape_id, v->prim_id = prim_id;
  v->p0 = to_double(patch->p[0]);
  v->e1 = to_double(patch->p[1]) - v->p0;
  v->e2 = to_double(patch->p[2]) - v->p0;
  v->n0 = to_double(patch->n[0]);
  v->dn1 = to_double(patch->n[1]) - v->n0;
  v->dn2 = to_double(patch->n[2]) - v->n0;
  v->ng = to_double(patch->ng);
  return true;
}

// Moves v to barycentrics (b1, b2) of its patch and updates the shading normal.
bool move_to(ManifoldVertex* v, double b1, double b2) {
  v->b1 = b1, v->b2 = b2;
  v->x = v->p0 + b1 * v->e1 + b2 * v->e2;
  const Vec3d N = v->n0 + b1 * v->dn1 + b2 * v->dn2;
  const double len = length(N);
  if (!(len > 0)) return false;
  const double sign = dot(N, v->ng) < 0 ? -1.0 : 1.0;
  v->n = N * (sign / len);
  // d(N/|N|) = (dN − n (n·dN)) / |N|; the sign flip carries through.
  v->dn_db1 = (v->dn1 - v->n * dot(v->n, v->dn1)) * (sign / len);
  v->dn_db2 = (v->dn2 - v->n * dot(v->n, v->dn2)) * (sign / len);
  return true;
}

// Where the ray o + t d meets v's plane, in double (Embree only chose the triangle).
bool place_along(ManifoldVertex* v, const Vec3d& o, const Vec3d& d) {
  const double denom = dot(v->ng, d);
  if (denom == 0) return false;
  const Vec3d r = o + d * (dot(v->ng, v->p0 - o) / denom) - v->p0;
  const double e11 = dot(v->e1, v->e1), e12 = dot(v->e1, v->e2), e22 = dot(v->e2, v->e2);
  const double r1 = dot(r, v->e1), r2 = dot(r, v->e2), det = e11 * e22 - e12 * e12;
  return move_to(v, (e22 * r1 - e12 * r2) / det, (e11 * r2 - e12 * r1) / det);
}

SurfaceHit vertex_surface(const ManifoldVertex& v) {
  const Vec3 p = to_float(v.x), ng = to_float(v.ng);
  return solved_vertex_hit(ChainFace{v.shape_id, v.prim_id, ng, dot(ng, p), p}, to_float(v.n));
}

// Gaussian elimination with partial pivoting: A (m × m, row-major) X = B (m × r).
// B is overwritten by X. False when A is singular to working precision.
bool solve_linear(std::array<double, kMaxUnknowns * kMaxUnknowns>& A, int m,
                  std::array<double, kMaxUnknowns * 2>& B, int r) {
  double scale = 0;
  for (int i = 0; i < m * m; ++i) scale = std::max(scale, std::fabs(A[i]));
  if (!(scale > 0)) return false;
  for (int col = 0; col < m; ++col) {
    int pivot = col;
    for (int row = col + 1; row < m; ++row)
      if (std::fabs(A[row * m + col]) > std::fabs(A[pivot * m + col])) pivot = row;
    if (!(std::fabs(A[pivot * m + col]) > 1e-14 * scale)) return false;
    if (pivot != col) {
      for (int j = 0; j < m; ++j) std::swap(A[col * m + j], A[pivot * m + j]);
      for (int j = 0; j < r; ++j) std::swap(B[col * r + j], B[pivot * r + j]);
    }
    for (int row = col + 1; row < m; ++row) {
      const double f = A[row * m + col] / A[col * m + col];
      if (f == 0) continue;
      for (int j = col; j < m; ++j) A[row * m + j] -= f * A[col * m + j];
      for (int j = 0; j < r; ++j) B[row * r + j] -= f * B[col * r + j];
    }
  }
  for (int row = m - 1; row >= 0; --row)
    for (int j = 0; j < r; ++j) {
      double v = B[row * r + j];
      for (int c = row + 1; c < m; ++c) v -= A[row * m + c] * B[c * r + j];
      B[row * r + j] = v / A[row * m + row];
    }
  return true;
}

// The chain being solved: vertices, fixed ends, the layers' relative indices.
struct Manifold {
  int k = 0;
  std::array<ManifoldVertex, kMaxSpecularChain> v;
  Vec3d x0, end;  // end: the light point, or the unit direction toward a distant light
  bool to_infinity = false;
  std::array<double, kMaxSpecularChain + 1> eta{};

  Vec3d previous(int j) const { return j == 0 ? x0 : v[j - 1].x; }

  // Constraint values, their largest normalised size, and (optionally) the
  // Jacobian in the vertices' barycentrics plus ∂c/∂(end ⊥ last leg) and
  // ∂c/∂(x0 ⊥ first leg) along the given orthonormal pairs.
  double residual(std::array<double, kMaxUnknowns>* c, std::array<double, kMaxUnknowns * kMaxUnknowns>* J,
                  std::array<double, kMaxUnknowns * 2>* dc_dend, const Vec3d* end_basis,
                  std::array<double, kMaxUnknowns * 2>* dc_dstart, const Vec3d* start_basis) const {
    const int m = 2 * k;
    if (J) J->fill(0);
    if (dc_dend) dc_dend->fill(0);
    if (dc_dstart) dc_dstart->fill(0);
    double worst = 0;
    for (int j = 0; j < k; ++j) {
      const ManifoldVertex& vj = v[j];
      Vec3d wa = previous(j) - vj.x;
      const double la = length(wa);
      wa = wa * (1 / la);
      Vec3d wb;
      double lb = 0;
      const bool last_at_infinity = to_infinity && j == k - 1;
      if (last_at_infinity) {
        wb = end;
      } else {
        wb = (j == k - 1 ? end : v[j + 1].x) - vj.x;
        lb = length(wb);
        wb = wb * (1 / lb);
      }
      const double ea = eta[j], eb = eta[j + 1];
      const Vec3d h = ea * wa + eb * wb;
      Vec3d s, t;
      tangent_frame(vj.n, &s, &t);
      const double cs = dot(h, s), ct = dot(h, t);
      (*c)[2 * j] = cs, (*c)[2 * j + 1] = ct;
      worst = std::max(worst, std::sqrt(cs * cs + ct * ct) / (ea + eb));
      if (!J) continue;
      // ∂h/∂x_{j-1} e = η_a (e − w_a (w_a·e)) / l_a, likewise for x_{j+1}; ∂h/∂x_j = −(both).
      const auto dh_prev = [&](const Vec3d& e) { return (e - wa * dot(wa, e)) * (ea / la); };
      const auto dh_next = [&](const Vec3d& e) {
        return last_at_infinity ? Vec3d{} : (e - wb * dot(wb, e)) * (eb / lb);
      };
      const double hn = dot(h, vj.n);
      const auto put = [&](int row, int col, const Vec3d& dh) {
        (*J)[row * m + col] = dot(dh, s);
        (*J)[(row + 1) * m + col] = dot(dh, t);
      };
      if (j > 0) {
        put(2 * j, 2 * (j - 1), dh_prev(v[j - 1].e1));
        put(2 * j, 2 * (j - 1) + 1, dh_prev(v[j - 1].e2));
      }
      if (j < k - 1) {
        put(2 * j, 2 * (j + 1), dh_next(v[j + 1].e1));
        put(2 * j, 2 * (j + 1) + 1, dh_next(v[j + 1].e2));
      }
      put(2 * j, 2 * j, Vec3d{} - dh_prev(vj.e1) - dh_next(vj.e1) - vj.dn_db1 * hn);
      put(2 * j, 2 * j + 1, Vec3d{} - dh_prev(vj.e2) - dh_next(vj.e2) - vj.dn_db2 * hn);
      if (dc_dend && j == k - 1 && !to_infinity)
        for (int q = 0; q < 2; ++q) {
          const Vec3d dh = dh_next(end_basis[q]);
          (*dc_dend)[(2 * j) * 2 + q] = dot(dh, s);
          (*dc_dend)[(2 * j + 1) * 2 + q] = dot(dh, t);
        }
      if (dc_dstart && j == 0)
        for (int q = 0; q < 2; ++q) {
          const Vec3d dh = dh_prev(start_basis[q]);
          (*dc_dstart)[q] = dot(dh, s);
          (*dc_dstart)[2 + q] = dot(dh, t);
        }
    }
    return worst;
  }

  // Re-walks the chain from x0 toward the proposed positions; false when a ray
  // misses the vertex's shape or meets anything else that is not pass-through.
  bool reproject(const Scene& scene, const std::array<Vec3d, kMaxSpecularChain>& proposed) {
    Vec3d o = x0;
    SurfaceHit from;
    for (int j = 0; j < k; ++j) {
      Vec3d d = proposed[j] - o;
      const double dist = length(d);
      if (!(dist > 0)) return false;
      d = d * (1 / dist);
      Ray ray = j == 0 ? Ray{to_float(o), to_float(d)} : scene.geometry.spawn_ray(from, to_float(d));
      std::optional<SurfaceHit> hit;
      for (int crossings = 0;; ++crossings) {
        if (crossings == 64) return false;
        hit = scene.geometry.intersect(ray, float(2 * dist) + 1e-3f);
        if (!hit) return false;
        if (!is_pass_through(scene, scene.shapes[hit->shape_id])) break;
        ray = scene.geometry.spawn_ray(*hit, ray.d);
      }
      if (hit->shape_id != v[j].shape_id) return false;
      if (hit->prim_id != v[j].prim_id && !set_patch(scene.geometry, hit->shape_id, hit->prim_id, &v[j])) return false;
      if (!place_along(&v[j], o, d)) return false;
      o = v[j].x;
      from = vertex_surface(v[j]);
    }
    return true;
  }
};

}  // namespace

std::optional<RefractedPath> solve_manifold_path(const Scene& scene, const SpecularChain& chain, const Vec3& x,
                                                 const Vec3& y, bool to_infinity, float lambda_nm) {
  const int k = chain.count;
  if (k == 0) return std::nullopt;  // nothing to solve: the planar form's straight line
  Manifold M;
  M.k = k;
  M.x0 = to_double(x);
  M.to_infinity = to_infinity;
  M.end = to_double(y);
  if (to_infinity) M.end = M.end * (1 / length(M.end));
  M.eta = chain_indices(scene, chain, x, lambda_nm);
  // Seed: the chain's own crossings, placed on their planes in double.
  std::array<bool, kMaxSpecularChain> entering{};
  for (int j = 0; j < k; ++j) {
    const ChainFace& f = chain.faces[j];
    const Vec3d seed = to_double(f.p) - M.x0;
    if (!set_patch(scene.geometry, f.shape_id, f.prim_id, &M.v[j]) ||
        !place_along(&M.v[j], M.x0, seed * (1 / length(seed))))
      return std::nullopt;
    entering[j] = chain_enters(chain, j, x);
  }

  std::array<double, kMaxUnknowns> c, c_trial, step;
  std::array<double, kMaxUnknowns * kMaxUnknowns> J;
  std::array<double, kMaxUnknowns * 2> rhs;
  const int m = 2 * k;
  double r = M.residual(&c, &J, nullptr, nullptr, nullptr, nullptr);
  double beta = 1;
  bool converged = r < kConstraintTolerance;
  for (int it = 0; it < kMaxNewtonSteps && !converged; ++it) {
    for (int i = 0; i < m; ++i) rhs[i] = -c[i];
    if (!solve_linear(J, m, rhs, 1)) return std::nullopt;
    for (int i = 0; i < m; ++i) step[i] = rhs[i];
    // Step control: halve until the re-projected chain lowers the residual.
    const double r_before = r;
    bool accepted = false;
    for (int halvings = 0; halvings < 6 && !accepted; ++halvings, beta *= 0.5) {
      Manifold trial = M;
      std::array<Vec3d, kMaxSpecularChain> proposed;
      for (int j = 0; j < k; ++j) {
        const ManifoldVertex& vj = M.v[j];
        proposed[j] = vj.x + (beta * step[2 * j]) * vj.e1 + (beta * step[2 * j + 1]) * vj.e2;
      }
      if (!trial.reproject(scene, proposed)) continue;
      const double r_trial = trial.residual(&c_trial, nullptr, nullptr, nullptr, nullptr, nullptr);
      if (!(r_trial < r)) continue;
      M = trial;
      c = c_trial;
      r = r_trial;
      accepted = true;
    }
    if (!accepted) return std::nullopt;
    beta = std::min(1.0, 4 * beta);  // undo the loop's last halving, then grow back
    converged = r < kConstraintTolerance;
    if (!converged && it + 1 >= kFirstStagnationCheck && r > kStagnationFactor * r_before) return std::nullopt;
    if (!converged) M.residual(&c, &J, nullptr, nullptr, nullptr, nullptr);
  }
  if (!converged) return std::nullopt;

  // The solution must cross (or mirror at) every face in the seed's sense, on the
  // same side of both normals (where they disagree the path tracer scatters in
  // the geometric frame instead). A mirror vertex's constraint is a crossing's
  // with equal indices, which a straight line through the face also meets.
  RefractedPath P;
  P.count = k;
  P.n = M.eta;
  for (int j = 0; j <= k; ++j) {
    const Vec3d from = M.previous(j);
    const Vec3d d = j < k ? M.v[j].x - from : (to_infinity ? M.end : M.end - from);
    P.dir[j] = to_float(d * (1 / length(d)));
  }
  for (int j = 0; j < k; ++j) {
    const ManifoldVertex& vj = M.v[j];
    const Vec3d d_in = to_double(P.dir[j]), d_out = to_double(P.dir[j + 1]);
    const double sense = entering[j] ? -1 : 1;
    const double sense_out = chain.faces[j].reflect ? -sense : sense;
    if (!(dot(d_in, vj.ng) * sense > 0 && dot(d_out, vj.ng) * sense_out > 0 && dot(d_in, vj.n) * sense > 0 &&
          dot(d_out, vj.n) * sense_out > 0))
      return std::nullopt;
    const Vec3 ng = to_float(vj.ng), p = to_float(vj.x);
    P.face[j] = ChainFace{vj.shape_id, vj.prim_id, ng, dot(ng, p), p, chain.faces[j].reflect};
    P.ns[j] = to_float(vj.n);
  }

  // Generalised geometry term from the constraint Jacobian.
  if (!to_infinity) {
    // dω_0 / dA_⊥: move y in the plane ⊥ the last leg, follow x_1, measure ω_0.
    Vec3d basis[2];
    tangent_frame(to_double(P.dir[k]), &basis[0], &basis[1]);
    M.residual(&c, &J, &rhs, basis, nullptr, nullptr);
    for (int i = 0; i < 2 * m; ++i) rhs[i] = -rhs[i];
    if (!solve_linear(J, m, rhs, 2)) return std::nullopt;
    const ManifoldVertex& v1 = M.v[0];
    const Vec3d w0 = v1.x - M.x0;
    const double l0 = length(w0);
    const Vec3d omega = w0 * (1 / l0);
    Vec3d d_omega[2];
    for (int q = 0; q < 2; ++q) {
      const Vec3d dx = rhs[q] * v1.e1 + rhs[2 + q] * v1.e2;
      d_omega[q] = (dx - omega * dot(omega, dx)) * (1 / l0);
    }
    P.geometry = length(cross(d_omega[0], d_omega[1]));
  } else {
    // dA_⊥(beam) / dA_⊥(x): move x0 ⊥ the first leg, follow the last vertex,
    // measure its offset across the incoming beam.
    Vec3d basis[2];
    tangent_frame(to_double(P.dir[0]), &basis[0], &basis[1]);
    M.residual(&c, &J, nullptr, nullptr, &rhs, basis);
    for (int i = 0; i < 2 * m; ++i) rhs[i] = -rhs[i];
    if (!solve_linear(J, m, rhs, 2)) return std::nullopt;
    const ManifoldVertex& vk = M.v[k - 1];
    Vec3d dq[2];
    for (int q = 0; q < 2; ++q) {
      const Vec3d dx = rhs[2 * (m - 2) + q] * vk.e1 + rhs[2 * (m - 1) + q] * vk.e2;
      dq[q] = dx - M.end * dot(M.end, dx);
    }
    P.geometry = length(cross(dq[0], dq[1]));
  }
  if (!(P.geometry > 0) || !std::isfinite(P.geometry)) return std::nullopt;
  return P;
}

}  // namespace chlorovdb
