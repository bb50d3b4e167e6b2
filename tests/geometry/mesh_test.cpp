#include "geometry/mesh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/constants.h"
#include "core/error.h"

using namespace chlorovdb;
namespace fs = std::filesystem;

namespace {

// A per-test scratch file under the system temp dir (removed at the end of the test).
class TempFile {
 public:
  TempFile(const std::string& name, const std::string& contents) {
    path_ = fs::temp_directory_path() / ("chlorovdb_geometry_" + std::to_string(::getpid()) + "_" + name);
    std::ofstream(path_, std::ios::binary) << contents;
  }
  ~TempFile() { fs::remove(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Unit cube as 8 shared vertices and 6 quads (CCW from outside): exercises triangulation.
const char* kCubeObj = R"(# unit cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
)";

std::string expect_input_error(const fs::path& file) {
  try {
    load_mesh(file);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for " << file;
  return {};
}

}  // namespace

TEST(Mesh, QuadHasUpwardNormalAndArea) {
  const TriangleMesh q = make_quad({0, 0, 0}, {2, 0, 0}, {0, 3, 0});
  EXPECT_EQ(q.triangle_count(), 2);
  EXPECT_FLOAT_EQ(mesh_area(q), 6.f);
  EXPECT_FALSE(is_closed(q));
  for (const Vec3& n : q.normals) EXPECT_EQ(n, Vec3(0, 0, 1));
}

TEST(Mesh, BoxIsClosedWithOutwardWinding) {
  const Bounds3 b{{0, 0, 0}, {2, 3, 4}};
  const TriangleMesh box = make_box(b);
  EXPECT_EQ(box.triangle_count(), 12);
  EXPECT_TRUE(is_closed(box));
  EXPECT_FLOAT_EQ(mesh_area(box), 2.f * (6 + 8 + 12));
  for (int t = 0; t < box.triangle_count(); ++t) {
    const Vec3 p0 = box.positions[box.indices[3 * t]], p1 = box.positions[box.indices[3 * t + 1]],
               p2 = box.positions[box.indices[3 * t + 2]];
    const Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
    const Vec3 centroid = (p0 + p1 + p2) / 3.f;
    EXPECT_GT(dot(ng, centroid - b.center()), 0.f) << "triangle " << t << " winds inward";
    EXPECT_EQ(ng, box.normals[box.indices[3 * t]]);
  }
}

TEST(Mesh, OpenOrInconsistentMeshesAreNotClosed) {
  TriangleMesh box = make_box({{0, 0, 0}, {1, 1, 1}});
  TriangleMesh holed = box;
  holed.indices.resize(holed.indices.size() - 3);
  EXPECT_FALSE(is_closed(holed));
  TriangleMesh flipped = box;
  std::swap(flipped.indices[1], flipped.indices[2]);
  EXPECT_FALSE(is_closed(flipped));
  EXPECT_FALSE(is_closed(make_disk({0, 0, 0}, {0, 0, 1}, 1.f, 16)));
  EXPECT_FALSE(is_closed(TriangleMesh{}));
}

TEST(Mesh, UvSphereIsClosedAndConvergesToSphereArea) {
  const TriangleMesh s = make_uv_sphere({1, 2, 3}, 2.f, 64, 128);
  EXPECT_TRUE(is_closed(s));
  EXPECT_NEAR(mesh_area(s), 4.f * kPi * 4.f, 0.01f * 4.f * kPi * 4.f);
  for (const Vec3& p : s.positions) EXPECT_NEAR(distance(p, {1, 2, 3}), 2.f, 1e-5f);
  TriangleMesh copy = s;
  EXPECT_EQ(drop_degenerate_triangles(copy), 0) << "pole bands must not emit degenerate triangles";
}

TEST(Mesh, DiskWindsTowardItsNormal) {
  const Vec3 n = normalize(Vec3{1, -2, 0.5f});
  const TriangleMesh d = make_disk({0, 0, 0}, n, 1.5f, 256);
  for (int t = 0; t < d.triangle_count(); ++t) {
    const Vec3 p0 = d.positions[d.indices[3 * t]], p1 = d.positions[d.indices[3 * t + 1]],
               p2 = d.positions[d.indices[3 * t + 2]];
    EXPECT_GT(dot(cross(p1 - p0, p2 - p0), n), 0.f);
  }
  EXPECT_NEAR(mesh_area(d), kPi * 1.5f * 1.5f, 1e-3f * kPi * 2.25f);
}

TEST(Mesh, MirroringTransformKeepsNormalsOutward) {
  const TriangleMesh box = transform_mesh(make_box({{0, 0, 0}, {1, 1, 1}}), Transform::scale({-1, 2, 1}));
  EXPECT_TRUE(is_closed(box));
  const Vec3 center{-0.5f, 1.f, 0.5f};
  for (int t = 0; t < box.triangle_count(); ++t) {
    const Vec3 p0 = box.positions[box.indices[3 * t]], p1 = box.positions[box.indices[3 * t + 1]],
               p2 = box.positions[box.indices[3 * t + 2]];
    const Vec3 ng = cross(p1 - p0, p2 - p0);
    EXPECT_GT(dot(ng, (p0 + p1 + p2) / 3.f - center), 0.f);
    EXPECT_GT(dot(ng, box.normals[box.indices[3 * t]]), 0.f);
  }
}

TEST(Mesh, DegenerateTrianglesAreDroppedAndCounted) {
  TriangleMesh m = make_quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  m.positions.push_back({2, 0, 0});
  m.positions.push_back({3, 0, 0});
  m.positions.push_back({4, 0, 0});
  m.indices.insert(m.indices.end(), {4, 5, 6, 0, 0, 1});  // collinear, repeated index
  EXPECT_EQ(drop_degenerate_triangles(m), 2);
  EXPECT_EQ(m.triangle_count(), 2);
}

TEST(MeshLoad, ObjQuadsAreTriangulatedAndWelded) {
  const TempFile file("cube.obj", kCubeObj);
  MeshLoadInfo info;
  const TriangleMesh m = load_mesh(file.path(), &info);
  EXPECT_EQ(m.triangle_count(), 12);
  EXPECT_EQ(info.degenerate_dropped, 0);
  EXPECT_EQ(info.source_meshes, 1);
  EXPECT_TRUE(is_closed(m));
  EXPECT_FLOAT_EQ(mesh_area(m), 6.f);
  EXPECT_TRUE(m.normals.empty());
}

TEST(MeshLoad, ObjDegenerateFaceIsDroppedAndCounted) {
  const std::string obj = std::string(kCubeObj) + "v 2 0 0\nv 3 0 0\nv 4 0 0\nf 9 10 11\n";
  const TempFile file("cube_degenerate.obj", obj);
  MeshLoadInfo info;
  const TriangleMesh m = load_mesh(file.path(), &info);
  EXPECT_EQ(info.degenerate_dropped, 1);
  EXPECT_EQ(m.triangle_count(), 12);
}

TEST(MeshLoad, PlyTetrahedronWithNormals) {
  const TempFile file("tetra.ply", R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
element face 4
property list uchar int vertex_indices
end_header
0 0 0 -1 -1 -1
1 0 0 1 0 0
0 1 0 0 1 0
0 0 1 0 0 1
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
)");
  const TriangleMesh m = load_mesh(file.path());
  EXPECT_EQ(m.triangle_count(), 4);
  EXPECT_TRUE(is_closed(m));
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (const Vec3& n : m.normals) EXPECT_NEAR(length(n), 1.f, 1e-6f);  // normalised on load
  EXPECT_NEAR(mesh_area(m), 1.5f + 0.5f * std::sqrt(3.f), 1e-5f);
}

TEST(MeshLoad, GltfNodesAreMergedWithTheirTransforms) {
  // One triangle mesh instanced by two nodes at z = +5 and z = -5 (buffer: 3 float3 positions, 3 uint16 indices).
  const TempFile file("two_nodes.gltf", R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0, "translation": [0, 0, 5]}, {"mesh": 0, "translation": [0, 0, -5]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
  ]
})");
  const TriangleMesh m = load_mesh(file.path());
  ASSERT_EQ(m.triangle_count(), 2);
  float z_min = 1e9f, z_max = -1e9f;
  for (uint32_t i : m.indices) z_min = std::min(z_min, m.positions[i].z), z_max = std::max(z_max, m.positions[i].z);
  EXPECT_FLOAT_EQ(z_min, -5.f);
  EXPECT_FLOAT_EQ(z_max, 5.f);
  EXPECT_FLOAT_EQ(mesh_area(m), 1.f);
}

namespace {

void put_u32(std::string& s, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) s[at + i] = char((v >> (8 * i)) & 0xffu);
}

// A GLB (binary glTF 2) holding one triangle: a JSON chunk, then a BIN chunk with
// 3 float3 positions and 3 uint16 indices.
std::string glb_triangle() {
  std::string json =
      R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
      R"("buffers":[{"byteLength":44}],)"
      R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],)"
      R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
      R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})";
  json.resize((json.size() + 3) / 4 * 4, ' ');
  std::string bin(44, '\0');
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(bin.data(), positions, sizeof positions);
  const uint16_t indices[3] = {0, 1, 2};
  std::memcpy(bin.data() + 36, indices, sizeof indices);
  std::string glb(12, '\0');
  glb.replace(0, 4, "glTF");
  put_u32(glb, 4, 2);
  for (const auto& [type, data] : {std::pair<const char*, const std::string&>{"JSON", json}, {"BIN\0", bin}}) {
    std::string chunk(8, '\0');
    put_u32(chunk, 0, uint32_t(data.size()));
    chunk.replace(4, 4, type, 4);
    glb += chunk + data;
  }
  put_u32(glb, 8, uint32_t(glb.size()));
  return glb;
}

}  // namespace

// Assimp 5.2 allocates a GLB chunk's declared length before reading it (a 57-byte file
// asked for 4.1 GB: fuzz/crashes/mesh/glb-json-chunk-length-*), so load_mesh checks
// the binary header against the file's size first.
TEST(MeshLoad, GlbLengthsBeyondTheFileAreRefused) {
  const std::string good = glb_triangle();
  const TempFile well_formed("triangle.glb", good);
  EXPECT_EQ(load_mesh(well_formed.path()).triangle_count(), 1);
  std::string json_chunk = good;
  put_u32(json_chunk, 12, 0xF70002ABu);
  const TempFile huge("huge_chunk.glb", json_chunk);
  std::string msg = expect_input_error(huge.path());
  EXPECT_NE(msg.find(huge.path().string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("GLB chunk 0 length = 4143973035"), std::string::npos) << msg;
  std::string bin_chunk = good;
  put_u32(bin_chunk, 20 + (good.size() - 20 - 44 - 8), 45);  // the BIN chunk one byte longer than its data
  const TempFile cut("cut_bin.glb", bin_chunk);
  msg = expect_input_error(cut.path());
  EXPECT_NE(msg.find("GLB chunk 1 length = 45"), std::string::npos) << msg;
  const TempFile truncated("truncated.glb", good.substr(0, good.size() - 4));
  msg = expect_input_error(truncated.path());
  EXPECT_NE(msg.find("GLB length = " + std::to_string(good.size())), std::string::npos) << msg;
  // The magic decides, not the extension: the same bytes named .gltf are checked too.
  const TempFile renamed("huge_chunk.gltf", json_chunk);
  EXPECT_NE(expect_input_error(renamed.path()).find("GLB chunk 0 length"), std::string::npos);
}

TEST(MeshLoad, MissingFileNamesTheFile) {
  const std::string msg = expect_input_error("/nonexistent/dir/plant_leaf.obj");
  EXPECT_NE(msg.find("plant_leaf.obj"), std::string::npos) << msg;
}

TEST(MeshLoad, FileWithoutTrianglesIsRejected) {
  const TempFile file("points_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  const std::string msg = expect_input_error(file.path());
  EXPECT_NE(msg.find(file.path().string()), std::string::npos) << msg;
  EXPECT_TRUE(msg.find("no triangles") != std::string::npos || msg.find("no faces") != std::string::npos) << msg;
}

TEST(MeshLoad, GarbageFileIsRejected) {
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage.push_back(char((i * 7919 + 13) % 256));
  const TempFile file("garbage.ply", garbage);
  const std::string msg = expect_input_error(file.path());
  EXPECT_NE(msg.find(file.path().string()), std::string::npos) << msg;
}

TEST(MeshLoad, NanCoordinateIsRejected) {
  const TempFile file("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string msg = expect_input_error(file.path());
  EXPECT_NE(msg.find(file.path().string()), std::string::npos) << msg;
}

// A binary PLY tetrahedron whose vertex 2 is `bad` in y. Assimp's vertex joining
// used to merge a NaN vertex into another one, so the NaN was never seen.
std::string binary_ply_tetrahedron(float bad) {
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, bad, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  s.append(reinterpret_cast<const char*>(v), sizeof(v));
  for (const auto& face : f) {
    s.push_back(char(3));
    s.append(reinterpret_cast<const char*>(face), sizeof(face));
  }
  return s;
}

TEST(MeshLoad, BinaryPlyWithNanOrInfVertexIsRejected) {
  const TempFile good("good.ply", binary_ply_tetrahedron(1.f));
  EXPECT_EQ(load_mesh(good.path()).positions.size(), 4u);
  for (const float bad : {std::nanf(""), INFINITY, -INFINITY}) {
    const TempFile file("nan.ply", binary_ply_tetrahedron(bad));
    const std::string msg = expect_input_error(file.path());
    EXPECT_NE(msg.find(file.path().string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("vertex 2"), std::string::npos) << msg;
    EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
  }
}

TEST(MeshLoad, AllDegenerateIsRejected) {
  const TempFile file("line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  const std::string msg = expect_input_error(file.path());
  EXPECT_NE(msg.find("degenerate"), std::string::npos) << msg;
}

// Assimp 5.2 reads past its buffer when a PLY header never ends (fuzz/crashes/mesh/crash-*:
// a segfault) and allocates whatever element counts the header declares, so load_mesh
// checks the header itself: every line one the format defines, an end_header, and
// declared elements that fit in the file.
TEST(MeshLoad, MalformedPlyHeaderIsRefusedNamingTheLine) {
  const std::string tail = binary_ply_tetrahedron(1.f).substr(binary_ply_tetrahedron(1.f).find("end_header\n") + 11);
  struct Case {
    std::string header, expected;
  };
  const Case cases[] = {
      // The shape of the fuzzer's crashes: end_header misspelt, so the header never ends.
      {"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 4\nproperty list uchar int vertex_indices\nend_hgader\n",
       "line 9"},
      {"ply\nformat binary_big_endian 2.0\nelement vertex 4\n", "line 2"},
      {"ply\nformat ascii 1.0\nelemty float y\nend_header\n", "line 3"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "line 3"},
      {"ply\nformat ascii 1.0\nelement vertex many\nend_header\n", "line 3"},
      {"ply\nformat ascii 1.0\nelement vertex 4\nproperty float\nend_header\n", "line 4"},
      {"ply\nformat ascii 1.0\nelement face 4\nproperty list uchar vertex_indices\nend_header\n", "line 4"},
      {"ply\nformat ascii 1.0\nelement vertex 4\nproperty quaternion x\nend_header\n", "line 4"},
      {"plyx\nformat ascii 1.0\n", "line 1"},
      // Assimp takes an unknown element's count from its name's leading digits: a
      // fuzzer's out-of-memory (fuzz/crashes/mesh/ply-element-name-with-a-count-oom-*).
      {"ply\nformat ascii 1.0\nelement 4294967295ex 4\nproperty float x\nend_header\n", "line 3"},
      // Assimp takes the magic in any case: a fuzzer's hang (fuzz/crashes/mesh/ply-capitalised-magic-*).
      {"Ply\nformat ascii 1.0\nentemel vertex 3\nproperty float x\n", "line 3"},
      {"PLYx\nformat ascii 1.0\n", "line 1"},
  };
  for (const Case& c : cases) {
    const TempFile file("bad_header.ply", c.header + tail);
    const std::string msg = expect_input_error(file.path());
    EXPECT_NE(msg.find(file.path().string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << c.header << " -> " << msg;
  }
  const TempFile file("no_end.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  EXPECT_NE(expect_input_error(file.path()).find("no end_header"), std::string::npos);
}

TEST(MeshLoad, PlyElementCountsBeyondTheFileAreRefused) {
  // 4294967295 vertices declared, 12 bytes of data: Assimp allocated 48 GB for it.
  const TempFile huge("huge.ply",
                      std::string("ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty float x\n"
                                  "property float y\nproperty float z\nelement face 1\n"
                                  "property list uchar int vertex_indices\nend_header\n") +
                          std::string(12, '\0'));
  const std::string msg = expect_input_error(huge.path());
  EXPECT_NE(msg.find(huge.path().string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("PLY element vertex = 4294967295"), std::string::npos) << msg;
  EXPECT_NE(msg.find("12 bytes"), std::string::npos) << msg;
  // Each binary face takes at least its list's count byte: 60 of them cannot fit in the 52
  // bytes after the vertices. ASCII counts at least two bytes per value.
  std::string binary = binary_ply_tetrahedron(1.f);
  binary.replace(binary.find("element face 4"), 14, "element face 60");
  const TempFile cut("cut.ply", binary);
  EXPECT_NE(expect_input_error(cut.path()).find("PLY element face = 60"), std::string::npos);
  const TempFile ascii("short.ply",
                       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 100\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(expect_input_error(ascii.path()).find("PLY element face = 100"), std::string::npos);
  // Well-formed files pass the check: ASCII with comments and CRLF, binary, the last value without a newline.
  const TempFile crlf("crlf.ply",
                      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info none\r\nelement vertex 3\r\n"
                      "property float x\r\nproperty float y\r\nproperty float z\r\nelement face 1\r\n"
                      "property list uchar int vertex_indices\r\nend_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2");
  EXPECT_EQ(load_mesh(crlf.path()).triangle_count(), 1);
  const TempFile good("good.ply", binary_ply_tetrahedron(1.f));
  EXPECT_EQ(load_mesh(good.path()).triangle_count(), 4);
  const TempFile upper("upper.ply", "PLY" + binary_ply_tetrahedron(1.f).substr(3));
  EXPECT_EQ(load_mesh(upper.path()).triangle_count(), 4);
}
