#pragma once
// Triangle meshes as plain data: loading (Assimp), procedural builders and the
// topological checks the scene needs (a medium can only be bounded by a closed mesh).
// Winding convention: counter-clockwise seen from outside, so the geometric
// normal cross(p1 - p0, p2 - p0) points out of a closed mesh.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/sampling.h"
#include "core/transform.h"
#include "core/vec.h"

namespace chlorovdb {

struct TriangleMesh {
  std::vector<Vec3> positions;   // metres
  std::vector<Vec3> normals;     // shading normals, unit; empty or one per position
  std::vector<Point2> uvs;       // empty or one per position
  std::vector<uint32_t> indices; // three per triangle
  int triangle_count() const { return int(indices.size() / 3); }
};

struct MeshLoadInfo {
  int degenerate_dropped = 0;  // zero-area (or needle) triangles removed on load
  int source_meshes = 0;       // meshes in the file that were merged
};

// Loads OBJ, PLY, glTF/GLB (anything Assimp reads) as one mesh: triangulated,
// identical vertices joined, every mesh of the file merged with its node
// transform applied. Shading normals / uvs are kept only if every mesh has them.
// Throws InputError naming the file when it cannot be read, holds no triangles,
// has non-finite coordinates, or every triangle is degenerate.
TriangleMesh load_mesh(const std::filesystem::path& file, MeshLoadInfo* info = nullptr);

// Removes triangles whose area is zero up to float rounding (their normal is
// undefined); returns how many were dropped. Unused vertices are kept.
int drop_degenerate_triangles(TriangleMesh& mesh);

// Builders. All produce CCW-outward triangles with shading normals and uvs.
// Quad spanned by corner + s*edge_u + t*edge_v, s,t in [0,1]; normal = normalize(cross(edge_u, edge_v)).
TriangleMesh make_quad(Vec3 corner, Vec3 edge_u, Vec3 edge_v);
// Closed axis-aligned box, flat outward normals (24 vertices, 12 triangles).
TriangleMesh make_box(const Bounds3& box);
// Flat disk facing `normal`, approximated by `segments` triangles around the centre.
TriangleMesh make_disk(Vec3 center, Vec3 normal, float radius, int segments);
// Closed latitude/longitude sphere: `rings` bands from pole to pole, `segments` around.
TriangleMesh make_uv_sphere(Vec3 center, float radius, int rings, int segments);

// True when every edge (vertices matched by position, so split normals do not
// open seams) is shared by exactly two triangles that traverse it in opposite
// directions: a watertight, consistently oriented surface that can bound a medium.
bool is_closed(const TriangleMesh& mesh);
// Sum of triangle areas, m².
float mesh_area(const TriangleMesh& mesh);
float triangle_area(const TriangleMesh& mesh, int triangle);
// Maps positions and normals; reverses the winding when the transform mirrors
// space so the geometric normal still points to the same (outer) side.
TriangleMesh transform_mesh(TriangleMesh mesh, const Transform& world_from_object);

}  // namespace chlorovdb
