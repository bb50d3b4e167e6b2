// The one translation unit of voxelize/ that includes OpenVDB (15-40 s to compile):
// mesh -> narrow band (meshToVolume) -> world-space distances -> fog grid -> .vdb.
#include "voxelize/voxelize.h"

#include <fmt/format.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <unordered_set>

#include "core/error.h"

namespace chlorovdb {
namespace {

using openvdb::Vec3d;
using FloatTree = openvdb::FloatTree;
using Int32Tree = openvdb::Int32Tree;
// Unregistered accessors: each trees outlives its accessors and is not modified meanwhile.
using FloatReader = openvdb::tree::ValueAccessor<const FloatTree, false>;
using IndexReader = openvdb::tree::ValueAccessor<const Int32Tree, false>;

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string source_of(const VoxelizeOptions& o) { return o.source_name.empty() ? std::string("<mesh>") : o.source_name; }

// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection, §5.1.5), by Voronoi
// region, and which feature it lies on: 0-2 vertex a, b, c; 3-5 edge ab, bc, ca; 6 the face.
struct ClosestPoint {
  Vec3d point = Vec3d(0.0);
  int feature = 6;
};

ClosestPoint closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, 0};
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return {a + ab * (d1 / (d1 - d3)), 3};
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return {a + ac * (d2 / (d2 - d6)), 5};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return {b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))), 4};
  const double denom = 1.0 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), 6};
}

// The output lattice: voxel (i, j, k) centred at world (i hx, j hy, k hz).
struct Lattice {
  Vec3d h;
  double half_diagonal;  // a voxel is entirely on one side of the surface if its centre is farther than this
  explicit Lattice(const Vec3& voxel_size)
      : h(voxel_size.x, voxel_size.y, voxel_size.z), half_diagonal(0.5 * h.length()) {}
  Vec3d world(const openvdb::Coord& ijk) const { return {ijk.x() * h.x(), ijk.y() * h.y(), ijk.z() * h.z()}; }
  // World extent of one voxel along unit direction g (the width of its box filter along g).
  double extent_along(const Vec3d& g) const {
    return std::abs(g.x()) * h.x() + std::abs(g.y()) * h.y() + std::abs(g.z()) * h.z();
  }
  double voxel_volume() const { return h.x() * h.y() * h.z(); }
  openvdb::math::Transform::Ptr transform() const {
    auto xform = openvdb::math::Transform::createLinearTransform(1.0);
    xform->preScale(h);
    return xform;
  }
};

// Part of [u - w/2, u + w/2] inside [-t/2, t/2], over w: a shell voxel's coverage along the normal.
double slab_coverage(double u, double w, double t) {
  const double overlap = std::min(u + 0.5 * w, 0.5 * t) - std::max(u - 0.5 * w, -0.5 * t);
  return std::clamp(overlap / w, 0.0, 1.0);
}

// The mesh in world space (double), vertices welded by position, with
// - the angle-weighted pseudo-normals of Baerentzen & Aanaes (2005): the sign of
//   dot(q - closest point, pseudo-normal of the closest feature) tells inside from outside for a
//   closed mesh, also at edges and corners;
// - vertex one-rings, to walk from a candidate triangle to a closer neighbour;
// - feature edges: boundary edges (one triangle) and sharp edges (faces meeting at over ~10°),
//   near which one box filter per voxel is not enough (see supersampled_coverage).
struct WorldMesh {
  std::vector<Vec3d> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<Vec3d> face_normals;                 // unit
  std::vector<Vec3d> vertex_normals;               // angle-weighted sums of face normals
  std::vector<std::array<Vec3d, 3>> edge_normals;  // per triangle, edges ab, bc, ca: sum of their faces' normals
  std::vector<std::array<bool, 3>> feature_edge;   // per triangle, edges ab, bc, ca: boundary or sharp
  std::vector<uint32_t> ring_start, ring;          // triangles around vertex v: ring[ring_start[v] .. ring_start[v+1])

  Vec3d pseudo_normal(size_t triangle, int feature) const {
    if (feature < 3) return vertex_normals[triangles[triangle][feature]];
    if (feature < 6) return edge_normals[triangle][feature - 3];
    return face_normals[triangle];
  }
};

WorldMesh world_mesh_of(const TriangleMesh& mesh) {
  WorldMesh w;
  // Weld by exact position (as is_closed does) so split normals / uvs do not open seams.
  std::map<std::array<float, 3>, uint32_t> weld;
  std::vector<uint32_t> id(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vec3& p = mesh.positions[v];
    const auto [it, inserted] =
        weld.emplace(std::array<float, 3>{p.x + 0.f, p.y + 0.f, p.z + 0.f}, uint32_t(w.points.size()));
    if (inserted) w.points.emplace_back(p.x, p.y, p.z);
    id[v] = it->second;
  }
  struct EdgeFaces {
    Vec3d normal_sum = Vec3d(0.0);
    Vec3d first = Vec3d(0.0);
    int count = 0;
    bool sharp = false;
  };
  w.vertex_normals.assign(w.points.size(), Vec3d(0.0));
  std::map<std::pair<uint32_t, uint32_t>, EdgeFaces> edges;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const openvdb::Vec3I tri(id[mesh.indices[3 * t]], id[mesh.indices[3 * t + 1]], id[mesh.indices[3 * t + 2]]);
    Vec3d n = (w.points[tri[1]] - w.points[tri[0]]).cross(w.points[tri[2]] - w.points[tri[0]]);
    if (!(n.length() > 0.0)) continue;  // collapsed by welding
    n.normalize();
    w.triangles.push_back(tri);
    w.face_normals.push_back(n);
    for (int k = 0; k < 3; ++k) {
      Vec3d e1 = w.points[tri[(k + 1) % 3]] - w.points[tri[k]], e2 = w.points[tri[(k + 2) % 3]] - w.points[tri[k]];
      e1.normalize();
      e2.normalize();
      w.vertex_normals[tri[k]] += std::acos(std::clamp(e1.dot(e2), -1.0, 1.0)) * n;
      EdgeFaces& e = edges[std::minmax(tri[k], tri[(k + 1) % 3])];
      if (e.count == 0) e.first = n;
      else if (n.dot(e.first) < 0.985) e.sharp = true;  // cos 10°
      e.normal_sum += n;
      ++e.count;
    }
  }
  std::vector<uint32_t> ring_count(w.points.size() + 1, 0);
  for (const openvdb::Vec3I& tri : w.triangles) {
    std::array<Vec3d, 3> normals;
    std::array<bool, 3> feature;
    for (int k = 0; k < 3; ++k) {
      const EdgeFaces& e = edges[std::minmax(tri[k], tri[(k + 1) % 3])];
      normals[k] = e.normal_sum;
      feature[k] = e.count == 1 || e.sharp;
      ++ring_count[tri[k]];
    }
    w.edge_normals.push_back(normals);
    w.feature_edge.push_back(feature);
  }
  w.ring_start.assign(w.points.size() + 1, 0);
  for (size_t v = 0; v < w.points.size(); ++v) w.ring_start[v + 1] = w.ring_start[v] + ring_count[v];
  w.ring.resize(w.ring_start.back());
  std::vector<uint32_t> fill(w.ring_start.begin(), w.ring_start.end() - 1);
  for (size_t t = 0; t < w.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) w.ring[fill[w.triangles[t][k]]++] = uint32_t(t);
  return w;
}

// Distance from p to segment ab.
double segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.lengthSqr(), 1e-300), 0.0, 1.0);
  return (p - (a + ab * t)).length();
}

// World distances near the surface for one band voxel. Start: the triangles OpenVDB found closest
// in index space to the voxel (near the surface also to its 26 neighbours). Then walk: while the
// closest point lies on an edge or vertex, try the triangles around it, moving to any that is
// closer. This finds the world-closest triangle where index and world metrics disagree (non-cubic
// voxels) and for points between lattice points (sub-voxels) even when triangles are far smaller
// than voxels.
class SurfaceDistance {
 public:
  struct Result {
    double distance = std::numeric_limits<double>::infinity();  // metres, >= 0
    Vec3d gradient = Vec3d(0.0);  // unit: from the closest surface point towards the point (face normal on the surface)
    bool inside = false;          // by pseudo-normal (closed meshes only)
  };

  SurfaceDistance(const WorldMesh& mesh, const Lattice& lattice) : mesh_(mesh), lattice_(lattice) {}

  // Gathers the candidates of voxel ijk (and of its 26 neighbours if `neighbours`); false if none.
  bool gather(const openvdb::Coord& ijk, IndexReader& index, bool neighbours) {
    count_ = 0;
    const int r = neighbours ? 1 : 0;
    for (int dz = -r; dz <= r; ++dz)
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const int32_t id = index.getValue(ijk.offsetBy(dx, dy, dz));
          if (id < 0 || size_t(id) >= mesh_.triangles.size()) continue;
          if (std::find(candidates_.begin(), candidates_.begin() + count_, id) == candidates_.begin() + count_)
            candidates_[count_++] = id;
        }
    return count_ > 0;
  }

  // Distance from world point p to the surface.
  Result at(const Vec3d& p) const {
    Result r;
    double best = std::numeric_limits<double>::infinity();
    ClosestPoint closest;
    int32_t best_id = -1;
    auto try_triangle = [&](int32_t id) {
      const openvdb::Vec3I& t = mesh_.triangles[size_t(id)];
      const ClosestPoint q = closest_point_on_triangle(p, mesh_.points[t[0]], mesh_.points[t[1]], mesh_.points[t[2]]);
      const double d2 = (p - q.point).lengthSqr();
      if (d2 < best) {
        best = d2, closest = q, best_id = id;
        return true;
      }
      return false;
    };
    for (int c = 0; c < count_; ++c) try_triangle(candidates_[c]);
    if (best_id < 0) return r;
    for (int step = 0; step < 64 && closest.feature != 6; ++step) {
      const openvdb::Vec3I& t = mesh_.triangles[size_t(best_id)];
      const int f = closest.feature;
      const std::array<uint32_t, 2> around = f < 3 ? std::array<uint32_t, 2>{t[f], t[f]}
                                                   : std::array<uint32_t, 2>{t[f - 3], t[(f - 2) % 3]};
      bool moved = false;
      for (int v = 0; v < (f < 3 ? 1 : 2); ++v)
        for (uint32_t i = mesh_.ring_start[around[v]]; i < mesh_.ring_start[around[v] + 1]; ++i)
          moved = try_triangle(int32_t(mesh_.ring[i])) || moved;
      if (!moved) break;
    }
    r.distance = std::sqrt(best);
    const Vec3d to_p = p - closest.point;
    r.inside = to_p.dot(mesh_.pseudo_normal(size_t(best_id), closest.feature)) < 0.0;
    // On the surface (up to rounding) the direction is the face normal; elsewhere the distance gradient.
    r.gradient = r.distance > 1e-9 * lattice_.half_diagonal ? to_p / r.distance : mesh_.face_normals[size_t(best_id)];
    return r;
  }

  // True if a feature edge (boundary or sharp) of a candidate triangle lies within `radius` of p.
  bool near_feature_edge(const Vec3d& p, double radius) const {
    for (int c = 0; c < count_; ++c) {
      const openvdb::Vec3I& t = mesh_.triangles[size_t(candidates_[c])];
      for (int k = 0; k < 3; ++k)
        if (mesh_.feature_edge[size_t(candidates_[c])][k] &&
            segment_distance(p, mesh_.points[t[k]], mesh_.points[t[(k + 1) % 3]]) < radius)
          return true;
    }
    return false;
  }

 private:
  const WorldMesh& mesh_;
  const Lattice& lattice_;
  std::array<int32_t, 27> candidates_{};
  int count_ = 0;
};

// Coverage of a voxel near a feature edge: the mean over 3 x 3 x 3 sub-voxels of each one's box
// filter along its own distance gradient. One filter along one gradient assumes the surface is
// flat across the voxel; it counts a voxel centred on a convex edge of a box as half covered
// instead of a quarter, and a shell's rounded rim (radius t/2, maybe under a voxel) as a slab.
// With sub-voxels that error is confined to the sub-voxels on the edge: 9 times smaller.
template <typename SubCoverage>
double supersampled_coverage(const Vec3d& p, const Lattice& lattice, SubCoverage&& sub_coverage) {
  constexpr int kSub = 3;
  double sum = 0;
  for (int k = 0; k < kSub; ++k)
    for (int j = 0; j < kSub; ++j)
      for (int i = 0; i < kSub; ++i) {
        const Vec3d offset((i + 0.5) / kSub - 0.5, (j + 0.5) / kSub - 0.5, (k + 0.5) / kSub - 0.5);
        sum += sub_coverage(p + offset * lattice.h);
      }
  return sum / (kSub * kSub * kSub);
}

struct Fog {
  openvdb::FloatGrid::Ptr grid;
  double filled_volume = 0;  // Σ coverage × voxel volume
  int64_t unresolved = 0;    // band voxels without a closest triangle nearby (kept with OpenVDB's distance)
};

// Voxelizes a (closed, for solid and spill) world-space mesh; see voxelize.h for the method.
Fog mesh_to_fog(const TriangleMesh& mesh, const VoxelizeOptions& o, const ProfileSampler& profile) {
  const bool shell = o.mode == VoxelizeMode::shell;
  const Lattice lattice(o.voxel_size);
  const WorldMesh world = world_mesh_of(mesh);

  // meshToVolume in index space with unit voxels: its distances and band widths are in voxel units.
  std::vector<openvdb::Vec3s> index_points;
  index_points.reserve(world.points.size());
  for (const Vec3d& p : world.points)
    index_points.emplace_back(float(p.x() / lattice.h.x()), float(p.y() / lattice.h.y()), float(p.z() / lattice.h.z()));
  const openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(index_points,
                                                                                            world.triangles);
  const detail::BandWidths band = detail::band_widths(o, profile.depth_range());
  // Distances are recomputed below, so OpenVDB's renormalization would only cost time.
  const int flags = openvdb::tools::DISABLE_RENORMALIZATION | (shell ? openvdb::tools::UNSIGNED_DISTANCE_FIELD : 0);
  // Background: no triangle. (Not `Grid g(int32_t(X))`: clang parses that as a function declaration.)
  const int32_t no_triangle = int32_t(openvdb::util::INVALID_IDX);
  openvdb::Int32Grid closest_triangle(no_triangle);
  const openvdb::math::Transform::Ptr unit_transform = openvdb::math::Transform::createLinearTransform(1.0);
  const openvdb::FloatGrid::Ptr sdf = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
      adapter, *unit_transform, band.exterior, band.interior, flags, &closest_triangle);

  // Topology of the fog: the band (its outer part is dropped below where coverage is 0) and,
  // for solids, the interior, whose deep part OpenVDB keeps as tiles.
  auto fog_tree = std::make_shared<FloatTree>(sdf->tree(), 0.f, 0.f, openvdb::TopologyCopy());
  if (!shell) {
    const auto interior = openvdb::tools::sdfInteriorMask(sdf->tree());
    fog_tree->topologyUnion(*interior);
  }
  if (profile.varies_with_position()) fog_tree->voxelizeActiveTiles(/*threaded=*/true);

  const double voxel_volume = lattice.voxel_volume();
  const double r_box = lattice.half_diagonal, half_t = 0.5 * double(o.thickness);
  // Index distance (voxel units) within which voxels can be partly covered, plus one.
  const float near_band = float((r_box + half_t) / std::min({lattice.h.x(), lattice.h.y(), lattice.h.z()})) + 1.f;
  std::vector<FloatTree::LeafNodeType*> leaves;
  fog_tree->getNodes(leaves);
  tbb::combinable<double> filled([] { return 0.0; });
  tbb::combinable<int64_t> unresolved([] { return int64_t(0); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()), [&](const tbb::blocked_range<size_t>& range) {
    FloatReader sdf_reader(sdf->tree());
    IndexReader index_reader(closest_triangle.tree());
    SurfaceDistance surface(world, lattice);
    double& filled_local = filled.local();
    for (size_t l = range.begin(); l != range.end(); ++l) {
      FloatTree::LeafNodeType& leaf = *leaves[l];
      for (openvdb::Index n = 0; n < FloatTree::LeafNodeType::SIZE; ++n) {
        if (!leaf.isValueOn(n)) continue;
        const openvdb::Coord ijk = leaf.offsetToGlobalCoord(n);
        const Vec3d p = lattice.world(ijk);
        float sdf_value = 0.f;
        double coverage = 1.0, depth = std::numeric_limits<double>::infinity();  // deep inside a solid
        if (sdf_reader.probeValue(ijk, sdf_value)) {  // in the band
          // Near the surface the 26 neighbours' triangles join the candidates (robust where two
          // parts of the surface are close); deeper, the voxel's own triangle and the walk suffice.
          if (!surface.gather(ijk, index_reader, std::abs(sdf_value) <= near_band)) {
            // Never seen in practice: OpenVDB's index-space distance, in the mean voxel size.
            ++unresolved.local();
            const double w = std::cbrt(voxel_volume), d = std::abs(sdf_value) * w;
            const double s = sdf_value < 0.f ? -d : d;
            coverage = shell ? slab_coverage(d, w, o.thickness) : std::clamp(0.5 - s / w, 0.0, 1.0);
            depth = shell ? std::max(0.0, half_t - d) : std::max(0.0, -s);
          } else if (shell) {
            const SurfaceDistance::Result d = surface.at(p);
            depth = std::max(0.0, half_t - d.distance);
            if (d.distance + r_box <= half_t) coverage = 1.0;  // the whole voxel is inside the shell
            else if (d.distance - r_box >= half_t) coverage = 0.0;
            else if (!surface.near_feature_edge(p, half_t + r_box))
              coverage = slab_coverage(d.distance, lattice.extent_along(d.gradient), o.thickness);
            else
              coverage = supersampled_coverage(p, lattice, [&](const Vec3d& q) {
                const SurfaceDistance::Result dq = surface.at(q);
                return slab_coverage(dq.distance, lattice.extent_along(dq.gradient) / 3.0, o.thickness);
              });
          } else {
            const SurfaceDistance::Result d = surface.at(p);
            const double s = sdf_value < 0.f ? -d.distance : d.distance;  // the voxel's sign: OpenVDB's flood fill
            depth = std::max(0.0, -s);
            if (s <= -r_box) coverage = 1.0;  // the whole voxel is inside
            else if (s >= r_box) coverage = 0.0;
            else if (!surface.near_feature_edge(p, r_box))
              coverage = std::clamp(0.5 - s / lattice.extent_along(d.gradient), 0.0, 1.0);
            else
              coverage = supersampled_coverage(p, lattice, [&](const Vec3d& q) {
                const SurfaceDistance::Result dq = surface.at(q);
                const double s_q = dq.inside ? -dq.distance : dq.distance;
                return std::clamp(0.5 - s_q / (lattice.extent_along(dq.gradient) / 3.0), 0.0, 1.0);
              });
          }
        }
        const float value =
            coverage > 0.0 ? float(coverage) * profile.value(Vec3(float(p.x()), float(p.y()), float(p.z())),
                                                             float(std::min(depth, 3e38)))
                           : 0.f;
        filled_local += coverage * voxel_volume;
        if (value > 0.f) leaf.setValueOnly(n, value);
        else leaf.setValueOff(n, 0.f);
      }
    }
  });

  Fog fog;
  fog.filled_volume = filled.combine(std::plus<double>());
  fog.unresolved = unresolved.combine(std::plus<int64_t>());
  // Deep interior tiles (profiles that do not vary with position): the deep value, fully covered.
  std::vector<std::pair<openvdb::CoordBBox, float>> tiles;
  const float deep = profile.varies_with_position() ? 0.f : profile.deep_value();
  for (auto it = fog_tree->cbeginValueOn(); it; ++it)
    if (it.isTileValue()) {
      openvdb::CoordBBox box;
      it.getBoundingBox(box);
      tiles.emplace_back(box, deep);
      fog.filled_volume += double(it.getVoxelCount()) * voxel_volume;
    }
  for (const auto& [box, value] : tiles) fog_tree->fill(box, value, value > 0.f);
  openvdb::tools::pruneInactive(*fog_tree);
  openvdb::tools::prune(*fog_tree);  // constant leaves (a uniform interior) become tiles

  fog.grid = openvdb::FloatGrid::create(fog_tree);
  fog.grid->setTransform(lattice.transform());
  return fog;
}

// Sizes of OpenVDB's tree nodes (a float leaf with its value buffer, the 16^3- and 32^3-child
// internal nodes) and the log2 of the voxels each spans per axis: the memory estimates count nodes.
using LowerNode = FloatTree::RootNodeType::ChildNodeType::ChildNodeType;
using UpperNode = FloatTree::RootNodeType::ChildNodeType;
constexpr openvdb::Index kLeafLog2 = FloatTree::LeafNodeType::TOTAL, kLowerLog2 = LowerNode::TOTAL,
                         kUpperLog2 = UpperNode::TOTAL;
constexpr double kFloatLeafBytes =
    double(sizeof(FloatTree::LeafNodeType) + sizeof(float) * FloatTree::LeafNodeType::SIZE);
constexpr double kLowerBytes = double(sizeof(LowerNode)), kUpperBytes = double(sizeof(UpperNode));

// Coord's own std::hash keeps 20 bits (OpenVDB's Coord::hash): past a million leaves a set
// keyed by it degrades to chains.
struct LeafOriginHash {
  size_t operator()(const openvdb::Coord& c) const {
    uint64_t h = uint64_t(uint32_t(c.x())) * 0x9E3779B97F4A7C15ull ^ uint64_t(uint32_t(c.y())) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(uint32_t(c.z())) * 0x165667B19E3779F9ull;
    h ^= h >> 29;  // the high bits reach the low ones, which pick the bucket
    return size_t(h);
  }
};
// The leaves seen so far, with a small direct-mapped cache in front: neighbouring pieces of a
// triangle mark mostly the same leaves, and the cache answers those without the set's probe.
struct LeafSet {
  std::unordered_set<openvdb::Coord, LeafOriginHash> set;
  std::vector<openvdb::Coord> recent = std::vector<openvdb::Coord>(4096, openvdb::Coord::max());
  void insert(const openvdb::Coord& c) {
    openvdb::Coord& slot = recent[LeafOriginHash{}(c) & (recent.size() - 1)];
    if (slot == c) return;
    slot = c;
    set.insert(c);
  }
  size_t size() const { return set.size(); }
};

// The leaves (8^3 voxels, keyed by their origin) within `reach` index voxels of the triangle
// (a, b, c) (index space), into `leaves` until it holds `max_leaves`: the triangle is halved
// across its longest edge (slivers, a needle's sides, split along their length only) until
// that edge is at most four leaves or `reach` long; then the leaves of the piece's bounding
// box grown by `reach` that lie within `reach` of its plane are marked (a piece is planar,
// so its size costs no precision). A superset of the leaves meshToVolume's band touches.
void collect_band_leaves(const openvdb::Vec3d& a, const openvdb::Vec3d& b, const openvdb::Vec3d& c, double reach,
                         LeafSet& leaves, size_t max_leaves) {
  if (leaves.size() >= max_leaves) return;
  const double leaf = double(1 << kLeafLog2);
  const double ab = (b - a).lengthSqr(), bc = (c - b).lengthSqr(), ca = (a - c).lengthSqr();
  if (const double longest = std::max({ab, bc, ca});
      longest > std::max(4.0 * leaf, reach) * std::max(4.0 * leaf, reach)) {
    if (ab == longest) {
      collect_band_leaves(a, 0.5 * (a + b), c, reach, leaves, max_leaves);
      collect_band_leaves(0.5 * (a + b), b, c, reach, leaves, max_leaves);
    } else if (bc == longest) {
      collect_band_leaves(a, b, 0.5 * (b + c), reach, leaves, max_leaves);
      collect_band_leaves(a, 0.5 * (b + c), c, reach, leaves, max_leaves);
    } else {
      collect_band_leaves(a, b, 0.5 * (c + a), reach, leaves, max_leaves);
      collect_band_leaves(0.5 * (c + a), b, c, reach, leaves, max_leaves);
    }
    return;
  }
  openvdb::Coord lo, hi;
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = int(std::floor((std::min({a[axis], b[axis], c[axis]}) - reach) / leaf));
    hi[axis] = int(std::floor((std::max({a[axis], b[axis], c[axis]}) + reach) / leaf));
  }
  // The plane's distance to a leaf's box: that to its centre less the box's half extent along the normal.
  openvdb::Vec3d n = (b - a).cross(c - a);
  const double n_length = n.length();
  n = n_length > 0.0 ? n / n_length : openvdb::Vec3d(0.0);
  const double half_extent = 0.5 * leaf * (std::abs(n.x()) + std::abs(n.y()) + std::abs(n.z()));
  for (int x = lo.x(); x <= hi.x(); ++x)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int z = lo.z(); z <= hi.z(); ++z) {
        const openvdb::Vec3d centre = leaf * openvdb::Vec3d(x + 0.5, y + 0.5, z + 0.5);
        if (std::abs(n.dot(centre - a)) - half_extent <= reach) leaves.insert(openvdb::Coord(x, y, z) << kLeafLog2);
      }
}

// Raises `e` to mesh_to_fog's trees counted by node: the leaves the band touches hold
// meshToVolume's distance (float) and closest triangle (int32, the same size), about as much
// again in its per-thread voxelization data, and the fog's float (at least e.stored_voxels of
// them); each of those four trees has the internal nodes over the band's leaves; 25 % over, as
// the area estimate. Counting stops once the bytes pass e.available_bytes or the leaves 2^31
// voxels, which check_estimate then refuses.
void add_tree_nodes(const TriangleMesh& mesh, const VoxelizeOptions& o, const detail::BandWidths& band,
                    VoxelEstimate& e) {
  const Vec3 h = o.voxel_size;
  const double reach = double(std::max(band.exterior, band.interior)) + 1.0;
  constexpr double kTrees = 4.0, kOverhead = 1.25;
  const double per_leaf = kTrees * kFloatLeafBytes, leaf_voxels = double(FloatTree::LeafNodeType::SIZE);
  double cap = kMaxVoxels / leaf_voxels + 1.0;
  if (e.available_bytes > 0) cap = std::min(cap, double(e.available_bytes) / (kOverhead * per_leaf) + 1.0);
  const auto max_leaves = size_t(cap);
  LeafSet leaves;
  for (int t = 0; t < mesh.triangle_count() && leaves.size() < max_leaves; ++t) {
    std::array<openvdb::Vec3d, 3> v;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.positions[mesh.indices[3 * t + k]];
      v[size_t(k)] = {double(p.x) / h.x, double(p.y) / h.y, double(p.z) / h.z};
    }
    collect_band_leaves(v[0], v[1], v[2], reach, leaves, max_leaves);
  }
  std::unordered_set<openvdb::Coord, LeafOriginHash> lower, upper;
  for (const openvdb::Coord& l : leaves.set) {
    lower.insert(l >> kLowerLog2);
    upper.insert(l >> kUpperLog2);
  }
  const double band_leaf_voxels = double(leaves.size()) * leaf_voxels;
  const double fog_beyond_band = std::max(0.0, e.stored_voxels - band_leaf_voxels) * sizeof(float);
  const double bytes = double(leaves.size()) * per_leaf + fog_beyond_band +
                       kTrees * (double(lower.size()) * kLowerBytes + double(upper.size()) * kUpperBytes);
  e.bytes = std::max(e.bytes, kOverhead * bytes);
  if (band_leaf_voxels > kMaxVoxels) e.band_voxels = std::max(e.band_voxels, band_leaf_voxels);
}

// The voxel columns of a height field spill: the layer y0 <= y <= y0 + depth · sample(x, z),
// bilinear between samples `cell` metres apart, sample (0, 0) at `origin`, over the voxel
// centres (i h.x, k h.z) inside the samples' footprint. Column (i, k) spans voxels j_lo .. j_hi(top).
struct HeightFieldColumns {
  const HeightField& f;
  Vec3d origin;
  double cell, depth;
  Vec3d h;
  int i0, i1, k0, k1, j_lo;
  HeightFieldColumns(const HeightField& field, const Vec3& o, float cell_size, const VoxelizeOptions& options)
      : f(field), origin(o.x, o.y, o.z), cell(cell_size), depth(options.depth), h(Lattice(options.voxel_size).h) {
    const double x_hi = origin.x() + cell * (f.nx - 1), z_hi = origin.z() + cell * (f.nz - 1);
    i0 = int(std::ceil(origin.x() / h.x())), i1 = int(std::floor(x_hi / h.x()));
    k0 = int(std::ceil(origin.z() / h.z())), k1 = int(std::floor(z_hi / h.z()));
    j_lo = int(std::floor(origin.y() / h.y() - 0.5));
  }
  // World y of the layer's top over column (i, k).
  double top(int i, int k) const {
    const double s = std::clamp((i * h.x() - origin.x()) / cell, 0.0, double(f.nx - 1));
    const double t = std::clamp((k * h.z() - origin.z()) / cell, 0.0, double(f.nz - 1));
    const int si = std::min(int(s), f.nx - 2), ti = std::min(int(t), f.nz - 2);
    const double fs = s - si, ft = t - ti;
    const double sample = (1 - ft) * ((1 - fs) * f.at(si, ti) + fs * f.at(si + 1, ti)) +
                          ft * ((1 - fs) * f.at(si, ti + 1) + fs * f.at(si + 1, ti + 1));
    return origin.y() + sample * depth;
  }
  int j_hi(double top) const { return int(std::ceil(top / h.y() + 0.5)); }
};

// Bytes of the tree height_field_to_fog builds. Every column starts at j_lo, so a node of
// OpenVDB's tree (leaf 8^3 voxels, internal nodes 128^3 and 4096^3) over a set of columns
// stacks from j_lo up to the tallest of them. Counting voxels alone misjudged spikes: a leaf
// over a one-column spike stores 8 voxels of its 512 and an internal node 128 of 2 million
// (a 3 x 2-sample field with one sample of 5e5 needed 1e6 voxels, was estimated at 10 MB
// and took 1.7 GB: fuzz/crashes/mesh/hf-one-tall-sample-*).
double height_field_tree_bytes(const HeightFieldColumns& c) {
  const std::array<int, 3> log2_dim{int(kLeafLog2), int(kLowerLog2), int(kUpperLog2)};
  const std::array<double, 3> node_bytes{kFloatLeafBytes, kLowerBytes, kUpperBytes};
  double bytes = 0;
  for (int level = 0; level < 3; ++level) {
    const int d = log2_dim[size_t(level)];  // >> on a negative int floors (C++20)
    const int ni = (c.i1 >> d) - (c.i0 >> d) + 1, nk = (c.k1 >> d) - (c.k0 >> d) + 1;
    std::vector<int> tallest(size_t(ni) * size_t(nk), std::numeric_limits<int>::min());
    for (int k = c.k0; k <= c.k1; ++k)
      for (int i = c.i0; i <= c.i1; ++i)
        if (const double top = c.top(i, k); top > c.origin.y()) {
          int& t = tallest[size_t((i >> d) - (c.i0 >> d)) + size_t(ni) * size_t((k >> d) - (c.k0 >> d))];
          t = std::max(t, c.j_hi(top));
        }
    for (const int j : tallest)
      if (j != std::numeric_limits<int>::min())
        bytes += double((j >> d) - (c.j_lo >> d) + 1) * node_bytes[size_t(level)];
  }
  return bytes;
}

// Height field spill over HeightFieldColumns: exact coverage along y; the footprint is point
// sampled at voxel centres in x and z (its edge is where the depth goes to 0, so it is soft already).
// The depth of a point is its vertical distance to the nearer of the floor and the liquid's top.
Fog height_field_to_fog(const HeightFieldColumns& c, const VoxelizeOptions& o, const ProfileSampler& profile) {
  const Lattice lattice(o.voxel_size);
  const Vec3d h = lattice.h;
  auto tree = std::make_shared<FloatTree>(0.f);
  openvdb::tree::ValueAccessor<FloatTree> acc(*tree);
  Fog fog;
  const double y0 = c.origin.y();
  for (int k = c.k0; k <= c.k1; ++k)
    for (int i = c.i0; i <= c.i1; ++i) {
      const double x = i * h.x(), z = k * h.z();
      const double top = c.top(i, k);
      if (!(top > y0)) continue;
      for (int j = c.j_lo, j1 = c.j_hi(top); j <= j1; ++j) {
        const double y = j * h.y();
        const double coverage =
            std::clamp((std::min(y + 0.5 * h.y(), top) - std::max(y - 0.5 * h.y(), y0)) / h.y(), 0.0, 1.0);
        if (coverage <= 0.0) continue;
        const double depth = std::max(0.0, std::min(y - y0, top - y));
        const float value = float(coverage) * profile.value(Vec3(float(x), float(y), float(z)), float(depth));
        fog.filled_volume += coverage * lattice.voxel_volume();
        if (value > 0.f) acc.setValue(openvdb::Coord(i, j, k), value);
      }
    }
  openvdb::tools::prune(*tree);
  fog.grid = openvdb::FloatGrid::create(tree);
  fog.grid->setTransform(lattice.transform());
  return fog;
}

// Names the grid, adds the metadata write_concentration_grids writes, writes the file, reports.
VoxelizeReport finish(Fog fog, const VoxelizeOptions& o, const VoxelEstimate& estimate, const std::string& provenance,
                      const std::filesystem::path& output) {
  openvdb::FloatGrid& grid = *fog.grid;
  VoxelizeReport report;
  report.estimate = estimate;
  report.filled_volume = fog.filled_volume;
  report.unresolved_voxels = fog.unresolved;
  report.provenance = provenance;
  const double voxel_volume = double(o.voxel_size.x) * o.voxel_size.y * o.voxel_size.z;
  bool any = false;
  for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
    const int64_t n = int64_t(it.getVoxelCount());
    report.active_voxels += n;
    report.amount += double(*it) * double(n) * voxel_volume;
    report.min_value = any ? std::min(report.min_value, *it) : *it;
    report.max_value = any ? std::max(report.max_value, *it) : *it;
    any = true;
  }
  if (!any)
    throw InputError(source_of(o), "--voxel-size", fmt::format("{}", o.voxel_size.x),
                     "the voxelized body is empty (no voxel holds a concentration > 0): are the voxels much larger "
                     "than the object, or is the concentration 0?");
  const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
  report.index_lo = {box.min().x(), box.min().y(), box.min().z()};
  report.index_hi = {box.max().x(), box.max().y(), box.max().z()};

  grid.setName(o.grid_name);
  grid.setGridClass(openvdb::GRID_FOG_VOLUME);
  grid.insertMeta("unit", openvdb::StringMetadata(o.unit));
  grid.insertMeta("scale", openvdb::FloatMetadata(1.f));
  grid.insertMeta("provenance", openvdb::StringMetadata(provenance));
  try {
    openvdb::io::File file(output.string());
    file.write(openvdb::GridPtrVec{fog.grid});
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError(output.string(), "", "", fmt::format("cannot write .vdb file ({})", e.what()));
  }
  return report;
}

std::string provenance_of(const VoxelizeOptions& o, const ProfileSampler& profile, const std::string& input) {
  return fmt::format("{}; source {}; made by chlorovdb voxelize",
                     o.command.empty() ? describe_options(o, profile) : o.command, input);
}

// OpenVDB's scale map refuses transforms whose determinant is under 3e-15
// (ScaleMap: "Non-zero scale values required"), i.e. voxels of about 14 µm and
// less when the mesh is in metres. Refused here, after the size estimate and
// before the conversion, as an InputError rather than an openvdb::ArithmeticError
// escaping at the end (docs/robustness.md, finding F6).
void check_voxel_volume(const VoxelizeOptions& o) {
  const Vec3 h = o.voxel_size;
  const double volume = double(h.x) * double(h.y) * double(h.z);
  constexpr double kMinVolume = 4e-15;  // OpenVDB's 3e-15 with a margin for rounding
  if (volume < kMinVolume)
    throw InputError(source_of(o), "--voxel-size", fmt::format("{},{},{}", h.x, h.y, h.z),
                     fmt::format("voxels of {:.3g} cubic units are smaller than an OpenVDB transform can hold "
                                 "({:.0e}; e.g. 15 µm cubes in metres): give the mesh and --voxel-size in millimetres "
                                 "or micrometres (--scale) and give the grid's length_unit in the scene to match",
                                 volume, kMinVolume));
}

}  // namespace

VoxelizeReport voxelize_mesh(const TriangleMesh& input, const VoxelizeOptions& o, const std::filesystem::path& output) {
  validate_options(o);
  initialize_openvdb();
  const std::string source = source_of(o);
  TriangleMesh mesh = o.world_from_input.is_identity() ? input : transform_mesh(input, o.world_from_input);
  if (mesh.indices.empty()) throw InputError(source, "", "", "mesh has no triangles");
  for (const Vec3& p : mesh.positions)
    if (!is_finite(p)) throw InputError(source, "", "", "mesh has a non-finite vertex coordinate (NaN or Inf)");
  const int triangles = mesh.triangle_count();
  drop_degenerate_triangles(mesh);
  if (mesh.indices.empty())
    throw InputError(source, "", "", fmt::format("all {} triangles are degenerate (zero area)", triangles));

  switch (o.mode) {
    case VoxelizeMode::solid: {
      if (!is_closed(mesh))
        throw InputError(source, "--mode", "solid",
                         "the mesh is not closed (it has open, non-manifold or inconsistently oriented edges); a "
                         "solid needs a watertight mesh. Use --mode shell --thickness T for open or thin surfaces");
      const Vec3 extent = detail::mesh_bounds(mesh).diagonal();
      if (!(extent.x > 0.f && extent.y > 0.f && extent.z > 0.f))
        throw InputError(source, "--mode", "solid",
                         fmt::format("the mesh's bounding box has zero volume ({} x {} x {} m): nothing to fill",
                                     extent.x, extent.y, extent.z));
      // Inward-facing winding: OpenVDB's sign does not care, the pseudo-normals do.
      if (detail::enclosed_volume(mesh) < 0.0)
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
      break;
    }
    case VoxelizeMode::shell: break;
    case VoxelizeMode::spill: mesh = extrude_footprint(mesh, spill_offset(mesh, o), source); break;
  }
  Bounds3 body = detail::mesh_bounds(mesh);
  if (o.mode == VoxelizeMode::shell) {
    body.lo -= Vec3(0.5f * o.thickness);
    body.hi += Vec3(0.5f * o.thickness);
  }
  const ProfileSampler profile(o.profile, body, o.unit, source);
  const detail::BandWidths band = detail::band_widths(o, profile.depth_range());
  check_index_range(body, double(std::max(band.exterior, band.interior)) + 1.0, o);
  VoxelEstimate estimate = estimate_voxels(mesh, o, profile);
  check_estimate(estimate, o);  // refuses the hopeless before visiting every triangle
  check_voxel_volume(o);
  add_tree_nodes(mesh, o, band, estimate);
  check_estimate(estimate, o);

  Fog fog = mesh_to_fog(mesh, o, profile);
  const std::string provenance =
      provenance_of(o, profile, fmt::format("{} ({} triangles)", source, input.triangle_count()));
  return finish(std::move(fog), o, estimate, provenance, output);
}

VoxelizeReport voxelize_height_field(const HeightField& f, const VoxelizeOptions& o,
                                     const std::filesystem::path& output) {
  validate_options(o);
  initialize_openvdb();
  const std::string source = source_of(o);
  if (o.mode != VoxelizeMode::spill)
    throw InputError(source, "--mode", std::string(to_string(o.mode)), "a height field can only make a spill (--mode spill)");
  if (f.nx < 2 || f.nz < 2 || f.values.size() != size_t(f.nx) * size_t(f.nz))
    throw InputError(source, "", fmt::format("{}x{} samples", f.nx, f.nz), "a height field needs at least 2x2 samples");
  const auto& m = o.world_from_input.matrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (m[r][c] != (r == c ? 1.f : 0.f))
        throw InputError(source, "--scale", "",
                         "a height field can only be moved (--translate); give its sample spacing with --cell-size");
  const Vec3 origin{m[0][3], m[1][3], m[2][3]};
  const float cell = o.height_field_cell > 0.f ? o.height_field_cell : o.voxel_size.x;
  float max_sample = 0.f;
  double sum = 0;
  for (float v : f.values) {
    if (!(std::isfinite(v) && v >= 0.f))
      throw InputError(source, "", fmt::format("{}", v), "a height field sample must be a finite number >= 0");
    max_sample = std::max(max_sample, v);
    sum += v;
  }
  const Bounds3 body{origin, origin + Vec3(cell * float(f.nx - 1), max_sample * o.depth, cell * float(f.nz - 1))};
  const ProfileSampler profile(o.profile, body, o.unit, source);
  check_index_range(body, 1.0, o);

  VoxelEstimate e;
  const Vec3 h = o.voxel_size;
  const double columns = double(cell) * (f.nx - 1) / h.x * double(cell) * (f.nz - 1) / h.z;
  e.body_voxels = sum * double(cell) * cell * o.depth / (double(h.x) * h.y * h.z) + 2.0 * columns;
  e.stored_voxels = e.body_voxels;
  e.band_voxels = 0;
  e.bytes = 4.0 * e.body_voxels;  // the values alone: refuses the hopeless before visiting every column
  e.available_bytes = o.memory_limit_bytes > 0 ? o.memory_limit_bytes : available_memory_bytes();
  check_estimate(e, o);
  check_voxel_volume(o);
  const HeightFieldColumns field_columns(f, origin, cell, o);
  e.bytes = 1.25 * height_field_tree_bytes(field_columns);  // the tree's nodes, 25 % over for writing it
  check_estimate(e, o);

  Fog fog = height_field_to_fog(field_columns, o, profile);
  return finish(std::move(fog), o, e, provenance_of(o, profile, fmt::format("{} ({}x{} samples)", source, f.nx, f.nz)),
                output);
}

VoxelizeReport voxelize_file(const std::filesystem::path& input, VoxelizeOptions o, const std::filesystem::path& output) {
  if (o.source_name.empty()) o.source_name = input.string();
  validate_options(o);  // before reading a possibly large file
  if (is_height_field_file(input)) {
    if (o.mode != VoxelizeMode::spill)
      throw InputError(o.source_name, "--mode", std::string(to_string(o.mode)),
                       "a height field can only make a spill (--mode spill)");
    return voxelize_height_field(load_height_field(input), o, output);
  }
  return voxelize_mesh(load_mesh(input), o, output);
}

}  // namespace chlorovdb
