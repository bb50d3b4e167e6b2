#include "geometry/geometry_scene.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/constants.h"
#include "core/float_bits.h"

namespace chlorovdb {
namespace {

// Floating-point error bound factor gamma(n) = n u / (1 - n u), u = 2^-24 (pbrt-v4, §6.8).
constexpr float gamma_bound(int n) {
  constexpr float u = 0x1p-24f;
  return float(n) * u / (1.f - float(n) * u);
}

// Triangle hit points are interpolated from float vertices (gamma(7) in pbrt's
// analysis). Embree's own plane test errs relative to the same vertex magnitudes;
// tests/geometry/spawn_ray_test.cpp finds no re-hits down to gamma(1), so 7 leaves margin.
constexpr float kTriangleErrorGamma = gamma_bound(7);
constexpr float kSphereErrorGamma = gamma_bound(5);  // reprojection onto the sphere
constexpr float kBoxErrorGamma = gamma_bound(3);     // o + t d off the face (the face's own axis is exact)
// Shadow rays stop this fraction of their length short of the target.
constexpr float kShadowEpsilon = 1e-4f;

struct MeshShape {
  TriangleMesh mesh;  // world space
  Distribution1D triangle_pdf;  // by area
  float area;
};

struct SphereShape {
  Vec3 center;
  float radius;
  int shape_id;
};

struct BoxShape {
  Bounds3 box;
  Vec3 inv_size;  // 1 / box.diagonal(), for a hit's uv
  int shape_id;
};

// Where a ray crosses a box's surface: its parameter and the face (prim_id order).
struct BoxCrossing {
  float t;
  int axis;
  bool max_face;
};

// Closest crossing of the box's surface with t in (0, t_max]: the entry face
// from outside, the exit face from inside (slab test, per axis the parameters of
// both planes; an axis the ray is parallel to either excludes the ray or is skipped).
// Only the crossing: GeometryScene::intersect builds the SurfaceHit of the nearest one.
std::optional<BoxCrossing> cross_box(const BoxShape& b, const Ray& ray, float t_max) {
  float t_near = -kInfinity, t_far = kInfinity;
  int axis_near = -1, axis_far = -1;
  for (int a = 0; a < 3; ++a) {
    if (ray.d[a] == 0.f) {
      if (ray.o[a] < b.box.lo[a] || ray.o[a] > b.box.hi[a]) return std::nullopt;
      continue;
    }
    const float inv = 1.f / ray.d[a];
    float t0 = (b.box.lo[a] - ray.o[a]) * inv, t1 = (b.box.hi[a] - ray.o[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) t_near = t0, axis_near = a;
    if (t1 < t_far) t_far = t1, axis_far = a;
  }
  if (t_near > t_far) return std::nullopt;
  float t;
  int axis;
  bool entering;
  if (t_near > 0.f) {
    t = t_near, axis = axis_near, entering = true;
  } else if (t_far > 0.f) {
    t = t_far, axis = axis_far, entering = false;
  } else {
    return std::nullopt;
  }
  if (!(t <= t_max) || axis < 0) return std::nullopt;
  // Entering across the max face means moving toward -axis; leaving across it, toward +axis.
  return BoxCrossing{t, axis, entering ? ray.d[axis] < 0.f : ray.d[axis] > 0.f};
}

SurfaceHit box_hit(const BoxShape& b, const Ray& ray, const BoxCrossing& c) {
  SurfaceHit hit;
  hit.t = c.t;
  hit.shape_id = b.shape_id;
  hit.prim_id = 2 * c.axis + (c.max_face ? 1 : 0);
  hit.p = ray.o + ray.d * c.t;
  hit.p[c.axis] = c.max_face ? b.box.hi[c.axis] : b.box.lo[c.axis];  // exactly on the face
  hit.p_error = kBoxErrorGamma * max_component(abs(ray.o) + abs(ray.d * c.t));
  hit.ng = Vec3(0.f);
  hit.ng[c.axis] = c.max_face ? 1.f : -1.f;
  hit.ns = hit.ng;
  const int u_axis = c.axis == 0 ? 1 : 0, v_axis = c.axis == 2 ? 1 : 2;
  hit.uv = {(hit.p[u_axis] - b.box.lo[u_axis]) * b.inv_size[u_axis],
            (hit.p[v_axis] - b.box.lo[v_axis]) * b.inv_size[v_axis]};
  return hit;
}

float box_area(const Bounds3& b) {
  const Vec3 s = b.diagonal();
  return 2.f * (s.x * s.y + s.y * s.z + s.z * s.x);
}

// Roots of |o + t d - c|² = r² in double, with the numerically stable form of
// the discriminant (Ray Tracing Gems ch. 7): b'² - a c = a (r² - |f|²) with f the
// part of (o - c) perpendicular to d, so far-away rays keep their precision.
bool intersect_sphere(const SphereShape& s, const RTCRay& ray, double* t_hit) {
  const double ox = double(ray.org_x) - s.center.x, oy = double(ray.org_y) - s.center.y,
               oz = double(ray.org_z) - s.center.z;
  const double dx = ray.dir_x, dy = ray.dir_y, dz = ray.dir_z;
  const double a = dx * dx + dy * dy + dz * dz;
  const double b = ox * dx + oy * dy + oz * dz;  // half of the usual b
  const double r = s.radius;
  const double c = ox * ox + oy * oy + oz * oz - r * r;
  const double fx = ox - b / a * dx, fy = oy - b / a * dy, fz = oz - b / a * dz;
  const double disc = a * (r * r - (fx * fx + fy * fy + fz * fz));
  if (disc < 0.0) return false;
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  const double t_near = ray.tnear, t_far = ray.tfar;
  if (t0 > t_near && t0 <= t_far) {
    *t_hit = t0;
    return true;
  }
  if (t1 > t_near && t1 <= t_far) {
    *t_hit = t1;
    return true;
  }
  return false;
}

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* s = static_cast<const SphereShape*>(args->geometryUserPtr);
  // Padded by a few ulps so float rounding never makes the box clip the sphere.
  const float r = s->radius * (1.f + 1e-6f) + 1e-6f * max_component(abs(s->center));
  RTCBounds* b = args->bounds_o;
  b->lower_x = s->center.x - r, b->lower_y = s->center.y - r, b->lower_z = s->center.z - r;
  b->upper_x = s->center.x + r, b->upper_y = s->center.y + r, b->upper_z = s->center.z + r;
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* s = static_cast<const SphereShape*>(args->geometryUserPtr);
  auto* rayhit = reinterpret_cast<RTCRayHit*>(args->rayhit);  // N == 1: only rtcIntersect1 is used
  double t;
  if (!intersect_sphere(*s, rayhit->ray, &t)) return;
  rayhit->ray.tfar = float(t);
  rayhit->hit.u = rayhit->hit.v = 0.f;
  rayhit->hit.Ng_x = rayhit->hit.Ng_y = rayhit->hit.Ng_z = 0.f;  // recomputed in double by GeometryScene
  rayhit->hit.primID = args->primID;
  rayhit->hit.geomID = args->geomID;
  rayhit->hit.instID[0] = args->context->instID[0];
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* s = static_cast<const SphereShape*>(args->geometryUserPtr);
  auto* ray = reinterpret_cast<RTCRay*>(args->ray);
  double t;
  if (intersect_sphere(*s, *ray, &t)) ray->tfar = -std::numeric_limits<float>::infinity();
}

RTCRay make_rtc_ray(const Ray& ray, float t_max) {
  RTCRay r;
  r.org_x = ray.o.x, r.org_y = ray.o.y, r.org_z = ray.o.z;
  r.dir_x = ray.d.x, r.dir_y = ray.d.y, r.dir_z = ray.d.z;
  r.tnear = 0.f;
  r.tfar = t_max;
  r.time = 0.f;
  r.mask = ~0u;
  r.id = 0;
  r.flags = 0;
  return r;
}

// Moves p by `offset` along n toward `w`'s side, then one more ulp away so
// rounding of the sum cannot pull it back onto the surface (pbrt-v4 OffsetRayOrigin).
Vec3 offset_origin(const SurfaceHit& hit, const Vec3& w) {
  const float d = hit.p_error * (std::fabs(hit.ng.x) + std::fabs(hit.ng.y) + std::fabs(hit.ng.z));
  Vec3 offset = hit.ng * d;
  if (dot(w, hit.ng) < 0.f) offset = -offset;
  Vec3 po = hit.p + offset;
  for (int a = 0; a < 3; ++a) {
    if (offset[a] > 0.f) po[a] = next_float_up(po[a]);
    else if (offset[a] < 0.f) po[a] = next_float_down(po[a]);
  }
  return po;
}

}  // namespace

struct GeometryScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::string last_error;
  std::vector<std::variant<MeshShape, const SphereShape*, BoxShape>> shapes;
  std::deque<SphereShape> spheres;  // stable addresses: Embree holds pointers to them
  std::vector<BoxShape> boxes;      // tested outside Embree
  int embree_shapes = 0;            // none: queries skip Embree
  Bounds3 bounds;

  // Embree's device and scene, made on the first mesh or sphere: a scene of
  // analytic boxes only (the cloud benchmark) never pays Embree's set-up or memory.
  void ensure_embree() {
    if (device) return;
    device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Embree: cannot create a device");
    rtcSetDeviceErrorFunction(
        device, [](void* user, RTCError, const char* message) { static_cast<Impl*>(user)->last_error = message ? message : ""; },
        this);
    scene = rtcNewScene(device);
    // Robust mode: watertight traversal, no accuracy-reducing shortcuts (rays must not leak out of closed media).
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    check("creating the scene");
  }

  void check(const char* what) const {
    const RTCError code = rtcGetDeviceError(device);
    if (code != RTC_ERROR_NONE) throw std::runtime_error(fmt::format("Embree: {} failed: {}", what, last_error));
  }

  SurfaceHit triangle_hit(const MeshShape& m, const RTCRayHit& rh) const {
    const TriangleMesh& mesh = m.mesh;
    const uint32_t i0 = mesh.indices[3 * rh.hit.primID], i1 = mesh.indices[3 * rh.hit.primID + 1],
                   i2 = mesh.indices[3 * rh.hit.primID + 2];
    const float b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.f - b1 - b2;
    const Vec3 &p0 = mesh.positions[i0], &p1 = mesh.positions[i1], &p2 = mesh.positions[i2];
    SurfaceHit hit;
    hit.t = rh.ray.tfar;
    hit.shape_id = int(rh.hit.geomID);
    hit.prim_id = int(rh.hit.primID);
    // Barycentric interpolation is more accurate than o + t d (error relative to the vertices, not t).
    hit.p = b0 * p0 + b1 * p1 + b2 * p2;
    hit.p_error = kTriangleErrorGamma * max_component(abs(b0 * p0) + abs(b1 * p1) + abs(b2 * p2));
    hit.ng = normalize(cross(p1 - p0, p2 - p0));
    if (!mesh.normals.empty()) {
      const Vec3 ns = b0 * mesh.normals[i0] + b1 * mesh.normals[i1] + b2 * mesh.normals[i2];
      const float len = length(ns);
      hit.ns = len > 0.f ? face_forward(ns / len, hit.ng) : hit.ng;
    } else {
      hit.ns = hit.ng;
    }
    if (!mesh.uvs.empty()) {
      const Point2 &t0 = mesh.uvs[i0], &t1 = mesh.uvs[i1], &t2 = mesh.uvs[i2];
      hit.uv = {b0 * t0.x + b1 * t1.x + b2 * t2.x, b0 * t0.y + b1 * t1.y + b2 * t2.y};
    } else {
      hit.uv = {b1, b2};
    }
    return hit;
  }

  static SurfaceHit sphere_hit(const SphereShape& s, const RTCRayHit& rh) {
    SurfaceHit hit;
    hit.t = rh.ray.tfar;
    hit.shape_id = s.shape_id;
    hit.prim_id = 0;
    // Reproject o + t d onto the sphere (in double) to remove the error of t.
    const double px = double(rh.ray.org_x) + double(rh.ray.tfar) * rh.ray.dir_x - s.center.x;
    const double py = double(rh.ray.org_y) + double(rh.ray.tfar) * rh.ray.dir_y - s.center.y;
    const double pz = double(rh.ray.org_z) + double(rh.ray.tfar) * rh.ray.dir_z - s.center.z;
    const double inv_len = 1.0 / std::sqrt(px * px + py * py + pz * pz);
    hit.ng = Vec3(float(px * inv_len), float(py * inv_len), float(pz * inv_len));
    hit.ns = hit.ng;
    hit.p = Vec3(float(s.center.x + s.radius * px * inv_len), float(s.center.y + s.radius * py * inv_len),
                 float(s.center.z + s.radius * pz * inv_len));
    hit.p_error = kSphereErrorGamma * max_component(abs(hit.p));
    const float phi = std::atan2(hit.ng.y, hit.ng.x);
    hit.uv = {(phi < 0.f ? phi + 2.f * kPi : phi) * kInv2Pi, std::acos(std::clamp(hit.ng.z, -1.f, 1.f)) * kInvPi};
    return hit;
  }
};

GeometryScene::GeometryScene() : impl_(std::make_unique<Impl>()) {}

GeometryScene::~GeometryScene() {
  if (!impl_) return;  // moved from
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

GeometryScene::GeometryScene(GeometryScene&&) noexcept = default;
GeometryScene& GeometryScene::operator=(GeometryScene&& other) noexcept {
  if (this != &other) {
    GeometryScene doomed(std::move(*this));  // releases our Embree objects
    impl_ = std::move(other.impl_);
  }
  return *this;
}

int GeometryScene::add_mesh(TriangleMesh mesh, const Transform& world_from_object) {
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    throw std::invalid_argument("add_mesh: normals must be empty or one per position");
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    throw std::invalid_argument("add_mesh: uvs must be empty or one per position");
  if (!world_from_object.is_identity()) mesh = transform_mesh(std::move(mesh), world_from_object);
  drop_degenerate_triangles(mesh);  // a zero-area triangle has no normal to shade with
  if (mesh.indices.empty()) throw std::invalid_argument("add_mesh: mesh has no non-degenerate triangles");

  impl_->ensure_embree();
  const int id = int(impl_->shapes.size());
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.positions.size()));
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int a = 0; a < 3; ++a) vertices[3 * v + a] = mesh.positions[v][a];
    impl_->bounds.extend(mesh.positions[v]);
  }
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(uint32_t), mesh.indices.size() / 3));
  std::copy(mesh.indices.begin(), mesh.indices.end(), indices);
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(impl_->scene, geom, unsigned(id));
  rtcReleaseGeometry(geom);
  impl_->check("adding a triangle mesh");

  std::vector<float> areas(mesh.triangle_count());
  for (int t = 0; t < mesh.triangle_count(); ++t) areas[t] = triangle_area(mesh, t);
  MeshShape shape{std::move(mesh), Distribution1D(areas), 0.f};
  shape.area = shape.triangle_pdf.total();
  impl_->shapes.emplace_back(std::move(shape));
  ++impl_->embree_shapes;
  return id;
}

int GeometryScene::add_sphere(Vec3 center, float radius) {
  if (!(radius > 0.f) || !is_finite(center)) throw std::invalid_argument("add_sphere: radius must be positive");
  impl_->ensure_embree();
  const int id = int(impl_->shapes.size());
  const SphereShape& s = impl_->spheres.emplace_back(SphereShape{center, radius, id});
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geom, 1);
  rtcSetGeometryUserData(geom, const_cast<SphereShape*>(&s));
  rtcSetGeometryBoundsFunction(geom, sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geom, sphere_intersect);
  rtcSetGeometryOccludedFunction(geom, sphere_occluded);
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(impl_->scene, geom, unsigned(id));
  rtcReleaseGeometry(geom);
  impl_->check("adding a sphere");
  impl_->shapes.emplace_back(&s);
  ++impl_->embree_shapes;
  impl_->bounds.extend(center - Vec3(radius));
  impl_->bounds.extend(center + Vec3(radius));
  return id;
}

int GeometryScene::add_box(const Bounds3& box) {
  const Vec3 size = box.diagonal();  // NaN fails the comparisons too
  if (!(size.x > 0.f && size.y > 0.f && size.z > 0.f) || !is_finite(box.lo) || !is_finite(box.hi))
    throw std::invalid_argument("add_box: the box must be finite and have positive extent on every axis");
  const int id = int(impl_->shapes.size());
  const BoxShape b{box, Vec3(1.f / size.x, 1.f / size.y, 1.f / size.z), id};
  impl_->shapes.emplace_back(b);
  impl_->boxes.push_back(b);
  impl_->bounds.extend(box.lo);
  impl_->bounds.extend(box.hi);
  return id;
}

void GeometryScene::commit() {
  if (!impl_->scene) return;
  rtcCommitScene(impl_->scene);
  impl_->check("building the BVH");
}

std::optional<SurfaceHit> GeometryScene::intersect(const Ray& ray, float t_max) const {
  std::optional<SurfaceHit> hit;
  if (impl_->embree_shapes > 0) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray = make_rtc_ray(ray, t_max);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      const auto& shape = impl_->shapes[rh.hit.geomID];
      if (const auto* mesh = std::get_if<MeshShape>(&shape)) hit = impl_->triangle_hit(*mesh, rh);
      else hit = Impl::sphere_hit(*std::get<const SphereShape*>(shape), rh);
      t_max = hit->t;
    }
  }
  const BoxShape* nearest_box = nullptr;
  BoxCrossing nearest{};
  for (const BoxShape& b : impl_->boxes)
    if (const auto c = cross_box(b, ray, t_max)) {
      nearest_box = &b;
      nearest = *c;
      t_max = c->t;
    }
  if (nearest_box) hit = box_hit(*nearest_box, ray, nearest);
  return hit;
}

bool GeometryScene::occluded(const Ray& ray, float t_max) const {
  for (const BoxShape& b : impl_->boxes)
    if (cross_box(b, ray, t_max)) return true;
  if (impl_->embree_shapes == 0) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = make_rtc_ray(ray, t_max);
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0.f;
}

bool GeometryScene::flat_face(int shape_id, int prim_id) const {
  const auto patch = surface_patch(shape_id, prim_id);
  if (!patch) return false;
  for (const Vec3& n : patch->n)
    if (dot(n, patch->ng) < 1.f - 1e-6f) return false;
  return true;
}

std::optional<SurfacePatch> GeometryScene::surface_patch(int shape_id, int prim_id) const {
  const auto& shape = impl_->shapes[shape_id];
  SurfacePatch patch;
  if (const auto* b = std::get_if<BoxShape>(&shape)) {
    const int axis = prim_id / 2, u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    const bool max_face = prim_id % 2 == 1;
    Vec3 corner = b->box.lo;
    corner[axis] = max_face ? b->box.hi[axis] : b->box.lo[axis];
    patch.p = {corner, corner, corner};
    patch.p[1][u] = b->box.hi[u];
    patch.p[2][v] = b->box.hi[v];
    patch.ng = Vec3(0.f);
    patch.ng[axis] = max_face ? 1.f : -1.f;
    patch.n = {patch.ng, patch.ng, patch.ng};
    return patch;
  }
  const auto* m = std::get_if<MeshShape>(&shape);
  if (!m) return std::nullopt;
  const TriangleMesh& mesh = m->mesh;
  const uint32_t* idx = &mesh.indices[3 * prim_id];
  for (int k = 0; k < 3; ++k) patch.p[k] = mesh.positions[idx[k]];
  patch.ng = normalize(cross(patch.p[1] - patch.p[0], patch.p[2] - patch.p[0]));
  for (int k = 0; k < 3; ++k) patch.n[k] = mesh.normals.empty() ? patch.ng : mesh.normals[idx[k]];
  return patch;
}

ShapeSample GeometryScene::sample_area(int shape_id, Point2 u) const {
  const auto& shape = impl_->shapes[shape_id];
  if (const auto* m = std::get_if<MeshShape>(&shape)) {
    float u_remapped;
    const int tri = m->triangle_pdf.sample(u.x, nullptr, &u_remapped);
    const auto b = sample_uniform_triangle({u_remapped, u.y});
    const TriangleMesh& mesh = m->mesh;
    const Vec3 &p0 = mesh.positions[mesh.indices[3 * tri]], &p1 = mesh.positions[mesh.indices[3 * tri + 1]],
               &p2 = mesh.positions[mesh.indices[3 * tri + 2]];
    // Triangle chosen with pmf area_i / A, point uniform on it with 1 / area_i: overall 1 / A.
    return {b[0] * p0 + b[1] * p1 + b[2] * p2, normalize(cross(p1 - p0, p2 - p0)), 1.f / m->area};
  }
  if (const auto* b = std::get_if<BoxShape>(&shape)) {
    // A face with probability area_face / A, then a uniform point on it: overall 1 / A.
    const Vec3 size = b->box.diagonal();
    const float face_area[3] = {size.y * size.z, size.z * size.x, size.x * size.y};
    float x = u.x * box_area(b->box);
    int face = 0;  // 2 axis + (1 on the max face), as prim_id
    while (face < 5 && x >= face_area[face / 2]) x -= face_area[face++ / 2];
    const int axis = face / 2, u_axis = axis == 0 ? 1 : 0, v_axis = axis == 2 ? 1 : 2;
    const bool max_face = face & 1;
    Vec3 p, n(0.f);
    p[axis] = max_face ? b->box.hi[axis] : b->box.lo[axis];
    p[u_axis] = b->box.lo[u_axis] + size[u_axis] * std::min(x / face_area[axis], 1.f);  // x: remapped u.x
    p[v_axis] = b->box.lo[v_axis] + size[v_axis] * u.y;
    n[axis] = max_face ? 1.f : -1.f;
    return {p, n, 1.f / box_area(b->box)};
  }
  const SphereShape& s = *std::get<const SphereShape*>(shape);
  const Vec3 n = sample_uniform_sphere(u);
  return {s.center + s.radius * n, n, 1.f / (4.f * kPi * s.radius * s.radius)};
}

float GeometryScene::area(int shape_id) const {
  const auto& shape = impl_->shapes[shape_id];
  if (const auto* m = std::get_if<MeshShape>(&shape)) return m->area;
  if (const auto* b = std::get_if<BoxShape>(&shape)) return box_area(b->box);
  const SphereShape& s = *std::get<const SphereShape*>(shape);
  return 4.f * kPi * s.radius * s.radius;
}

int GeometryScene::shape_count() const { return int(impl_->shapes.size()); }

Bounds3 GeometryScene::bounds() const { return impl_->bounds; }

Ray GeometryScene::spawn_ray(const SurfaceHit& hit, const Vec3& dir) const { return {offset_origin(hit, dir), dir}; }

Ray GeometryScene::spawn_ray_to(const SurfaceHit& hit, const Vec3& p_target, float* t_max) const {
  const Vec3 o = offset_origin(hit, p_target - hit.p);
  const Vec3 d = p_target - o;
  const float dist = length(d);
  // Stop short of a surface the target may lie on: relative gap plus the
  // target's own float error (which grows with its distance from the origin).
  const float gap = kShadowEpsilon * dist + kTriangleErrorGamma * max_component(abs(p_target));
  *t_max = std::max(0.f, dist - gap);
  return {o, dist > 0.f ? d / dist : hit.ng};
}

}  // namespace chlorovdb
