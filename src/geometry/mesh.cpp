#include "geometry/mesh.h"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "core/constants.h"
#include "core/error.h"

namespace chlorovdb {
namespace {

Vec3 triangle_cross(const TriangleMesh& mesh, int tri) {
  const Vec3& p0 = mesh.positions[mesh.indices[3 * tri]];
  const Vec3& p1 = mesh.positions[mesh.indices[3 * tri + 1]];
  const Vec3& p2 = mesh.positions[mesh.indices[3 * tri + 2]];
  return cross(p1 - p0, p2 - p0);
}

// A triangle is degenerate when its area is at float-rounding level relative to
// its longest edge (|e0 x e1| <= 1e-6 * longest²): its normal is then noise.
bool is_degenerate(const TriangleMesh& mesh, int tri) {
  const uint32_t i0 = mesh.indices[3 * tri], i1 = mesh.indices[3 * tri + 1], i2 = mesh.indices[3 * tri + 2];
  if (i0 == i1 || i1 == i2 || i2 == i0) return true;
  const Vec3 &p0 = mesh.positions[i0], &p1 = mesh.positions[i1], &p2 = mesh.positions[i2];
  const float longest_sq =
      std::max({length_squared(p1 - p0), length_squared(p2 - p1), length_squared(p0 - p2)});
  const float area2 = length(cross(p1 - p0, p2 - p0));
  return !(area2 > 1e-6f * longest_sq);  // also catches NaN
}

// Shading normals that are zero or non-finite are replaced by the area-weighted
// average of the adjacent faces' geometric normals; returns how many were.
int repair_normals(TriangleMesh& mesh) {
  std::vector<uint8_t> bad(mesh.normals.size(), 0);
  int repaired = 0;
  for (size_t i = 0; i < mesh.normals.size(); ++i) {
    const float len = length(mesh.normals[i]);
    if (std::isfinite(len) && len > 0.f) {
      mesh.normals[i] = mesh.normals[i] / len;
    } else {
      bad[i] = 1;
      mesh.normals[i] = Vec3(0.f);
      ++repaired;
    }
  }
  if (repaired == 0) return 0;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 area_normal = triangle_cross(mesh, t);
    for (int k = 0; k < 3; ++k)
      if (bad[mesh.indices[3 * t + k]]) mesh.normals[mesh.indices[3 * t + k]] += area_normal;
  }
  for (size_t i = 0; i < mesh.normals.size(); ++i)
    if (bad[i]) {
      const float len = length(mesh.normals[i]);
      mesh.normals[i] = len > 0.f ? mesh.normals[i] / len : Vec3(0.f, 0.f, 1.f);  // unreferenced vertex
    }
  return repaired;
}

// Bytes of one PLY scalar type; 0 if the word is not one.
int ply_type_size(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// Assimp 5.2's PLY reader trusts the header: without an end_header line it reads
// past its buffer (a crash: upstream assimp#4843, fixed after 5.2.5), and it allocates
// what the header declares before reading any data (4294967295 vertices in a
// 200-byte file asked for 48 GB, and a count can hide in an element's name: see
// below). So a file starting with "ply" in any case (the magic
// Assimp's reader accepts, whatever the file's extension) is checked first:
// every header line must be one the format defines, the header must end, and the
// declared elements must fit in the bytes after it (binary: each instance takes its
// scalar properties plus each list's count; ASCII: at least two bytes, a digit and
// a separator, per property).
void check_ply_header(const std::filesystem::path& file, const std::string& name) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  const auto lowercase = [](std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  if (!std::getline(in, line) || lowercase(line.substr(0, 3)) != "ply") return;  // not a PLY file
  const auto refuse = [&](int line_number, const std::string& problem) {
    return InputError(name, fmt::format("PLY header line {}", line_number), line.substr(0, 80), problem);
  };
  if (const std::string magic = lowercase(line); magic != "ply" && magic != "ply\r")
    throw refuse(1, "the first line must be \"ply\"");
  struct Element {
    std::string name;
    uint64_t count = 0;
    uint64_t bytes_each = 0;
  };
  std::vector<Element> elements;
  bool binary = false, has_format = false;
  constexpr int kMaxHeaderLines = 10000;
  for (int number = 2; number <= kMaxHeaderLines && std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.size() > 1000) throw refuse(number, "is longer than 1000 characters: not a PLY header line");
    std::istringstream words(line);
    std::string keyword, a, b, c, extra;
    words >> keyword >> a >> b >> c;
    if (keyword == "comment" || keyword == "obj_info") continue;
    words >> extra;
    if (keyword == "format") {
      if (has_format || number != 2 || !(a == "ascii" || a == "binary_little_endian" || a == "binary_big_endian") ||
          b != "1.0" || !c.empty())
        throw refuse(number, "must be \"format ascii|binary_little_endian|binary_big_endian 1.0\" on line 2");
      binary = a != "ascii";
      has_format = true;
    } else if (keyword == "element") {
      Element e{a, 0, 0};
      if (!has_format || a.empty() || !c.empty() ||
          std::from_chars(b.data(), b.data() + b.size(), e.count).ec != std::errc() || b.empty())
        throw refuse(number, "must be \"element NAME COUNT\" after the format line");
      // Assimp reads an element of a name it does not know from the name's first
      // character on, so it takes the count from a name's leading digits
      // ("element 4294967295ex 4" asked for 96 GB).
      if (!std::isalpha(static_cast<unsigned char>(a[0])) && a[0] != '_')
        throw refuse(number, "an element's name must start with a letter or '_'");
      elements.push_back(e);
    } else if (keyword == "property") {
      const bool list = a == "list";
      const int bytes = ply_type_size(list ? b : a);
      const bool well_formed = list ? ply_type_size(c) > 0 && !extra.empty() : !b.empty() && c.empty();
      if (elements.empty() || bytes == 0 || !well_formed)
        throw refuse(number, "must be \"property TYPE NAME\" or \"property list COUNT_TYPE TYPE NAME\" after an element");
      elements.back().bytes_each += binary ? uint64_t(bytes) : 2;  // an empty list is just its count
    } else if (keyword == "end_header" && a.empty()) {
      if (!has_format) throw refuse(number, "the header has no format line");
      const uint64_t size = std::filesystem::file_size(file);
      // An ASCII file's last value may lack its separator.
      const uint64_t data = size - std::min<uint64_t>(size, uint64_t(in.tellg())) + (binary ? 0 : 1);
      double needed = 0;  // in double: counts up to 2^64 times bytes cannot overflow
      for (const Element& e : elements) {
        needed += double(e.count) * double(e.bytes_each);
        if (needed > double(data))
          throw InputError(name, fmt::format("PLY element {}", e.name), fmt::format("{}", e.count),
                           fmt::format("the header declares {} elements of at least {} bytes each, more than the "
                                       "{} bytes of data after the header (truncated or corrupt file)",
                                       e.count, e.bytes_each, data));
      }
      return;
    } else {
      throw refuse(number, "is not a PLY header line (format, element, property, comment, obj_info or end_header)");
    }
  }
  throw InputError(name, "", "", fmt::format("the PLY header has no end_header line within {} lines", kMaxHeaderLines));
}

// Assimp 5.2's binary glTF readers allocate what a chunk header declares before
// reading it: a 57-byte GLB whose JSON chunk declared 0xF70002AB bytes asked for
// 4.1 GB (fuzz/crashes/mesh/glb-json-chunk-length-*). So a file starting with the
// binary glTF magic (which Assimp accepts whatever the extension) is checked first:
// the declared total length and every chunk must fit in the file. Version 1 has one
// content block of declared length after a 20-byte header; version 2 a 12-byte
// header and then chunks, each an 8-byte header (length, type) and its data.
void check_glb_header(const std::filesystem::path& file, const std::string& name) {
  std::ifstream in(file, std::ios::binary);
  std::array<unsigned char, 20> header{};
  in.read(reinterpret_cast<char*>(header.data()), 12);
  if (in.gcount() < 4 || std::memcmp(header.data(), "glTF", 4) != 0) return;  // not a binary glTF file
  const uint64_t size = std::filesystem::file_size(file);
  const auto u32 = [](const unsigned char* b) {  // GLB is little-endian whatever the host
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
  };
  const auto refuse = [&](const std::string& key, uint64_t value, uint64_t offset) {
    return InputError(name, key, fmt::format("{}", value),
                      fmt::format("declares more bytes than the {} left in the {}-byte file after offset {} "
                                  "(truncated or corrupt binary glTF)",
                                  size - std::min(size, offset), size, offset));
  };
  if (in.gcount() < 12) throw InputError(name, "", "", "the binary glTF header is shorter than 12 bytes");
  const uint32_t version = u32(&header[4]), length = u32(&header[8]);
  if (length > size) throw refuse("GLB length", length, 0);
  if (version == 1) {
    in.read(reinterpret_cast<char*>(&header[12]), 8);
    if (in.gcount() < 8) throw InputError(name, "", "", "the binary glTF 1 header is shorter than 20 bytes");
    if (const uint32_t content = u32(&header[12]); content > size - 20) throw refuse("GLB content length", content, 20);
    return;
  }
  uint64_t offset = 12;
  for (int chunk = 0; offset + 8 <= size; ++chunk) {
    std::array<unsigned char, 8> chunk_header{};
    in.seekg(std::streamoff(offset));
    in.read(reinterpret_cast<char*>(chunk_header.data()), 8);
    if (in.gcount() < 8) break;
    const uint32_t chunk_length = u32(chunk_header.data());
    if (chunk_length > size - offset - 8)
      throw refuse(fmt::format("GLB chunk {} length", chunk), chunk_length, offset + 8);
    offset += 8 + uint64_t(chunk_length);
  }
}

}  // namespace

TriangleMesh load_mesh(const std::filesystem::path& file, MeshLoadInfo* info) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError(name, "", "", "mesh file not found or not a file");

  check_ply_header(file, name);
  check_glb_header(file, name);

  Assimp::Importer importer;
  // Points and lines cannot bound anything: drop them instead of failing.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  // Vertices are checked before post-processing: JoinIdenticalVertices silently
  // merges a NaN vertex into another one, so the file's NaN would never be seen.
  const aiScene* scene = importer.ReadFile(name, 0);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError(name, "", "", fmt::format("cannot read mesh: {}", importer.GetErrorString()));
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned v = 0; v < scene->mMeshes[m]->mNumVertices; ++v) {
      const aiVector3D& p = scene->mMeshes[m]->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw InputError(name, "", "",
                         fmt::format("vertex {} of mesh {} has a non-finite coordinate ({}, {}, {})", v, m, p.x, p.y, p.z));
    }
  scene = importer.ApplyPostProcessing(flags);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError(name, "", "", fmt::format("cannot read mesh: {}", importer.GetErrorString()));

  bool all_normals = scene->mNumMeshes > 0, all_uvs = scene->mNumMeshes > 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    all_normals = all_normals && scene->mMeshes[m]->HasNormals();
    all_uvs = all_uvs && scene->mMeshes[m]->HasTextureCoords(0);
  }

  TriangleMesh mesh;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    const uint32_t base = uint32_t(mesh.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      mesh.positions.push_back({p.x, p.y, p.z});
      if (all_normals) mesh.normals.push_back({am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z});
      if (all_uvs) mesh.uvs.push_back({am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y});
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // SortByPType already removed points and lines
      for (int k = 0; k < 3; ++k) mesh.indices.push_back(base + face.mIndices[k]);
    }
  }

  if (mesh.indices.empty()) throw InputError(name, "", "", "mesh has no triangles");
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    if (!is_finite(mesh.positions[v]))
      throw InputError(name, "", "", fmt::format("vertex {} has a non-finite coordinate (NaN or Inf)", v));

  const int triangles_in_file = mesh.triangle_count();
  const int dropped = drop_degenerate_triangles(mesh);
  if (mesh.indices.empty())
    throw InputError(name, "", "", fmt::format("all {} triangles are degenerate (zero area)", triangles_in_file));
  repair_normals(mesh);

  if (info) {
    info->degenerate_dropped = dropped;
    info->source_meshes = int(scene->mNumMeshes);
  }
  return mesh;
}

int drop_degenerate_triangles(TriangleMesh& mesh) {
  const int n = mesh.triangle_count();
  size_t kept = 0;
  for (int t = 0; t < n; ++t) {
    if (is_degenerate(mesh, t)) continue;
    for (int k = 0; k < 3; ++k) mesh.indices[kept + k] = mesh.indices[3 * t + k];
    kept += 3;
  }
  mesh.indices.resize(kept);
  return n - int(kept / 3);
}

TriangleMesh make_quad(Vec3 corner, Vec3 edge_u, Vec3 edge_v) {
  TriangleMesh mesh;
  const Vec3 n = normalize(cross(edge_u, edge_v));
  mesh.positions = {corner, corner + edge_u, corner + edge_u + edge_v, corner + edge_v};
  mesh.normals = {n, n, n, n};
  mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

TriangleMesh make_box(const Bounds3& box) {
  const Vec3 lo = box.lo, d = box.diagonal();
  const Vec3 ex{d.x, 0, 0}, ey{0, d.y, 0}, ez{0, 0, d.z};
  // Each face as a quad whose cross(edge_u, edge_v) points outward.
  const std::array<std::array<Vec3, 3>, 6> faces{{
      {lo, ey, ex},            // -z
      {lo + ez, ex, ey},       // +z
      {lo, ex, ez},            // -y
      {lo + ey, ez, ex},       // +y
      {lo, ez, ey},            // -x
      {lo + ex, ey, ez},       // +x
  }};
  TriangleMesh mesh;
  for (const auto& f : faces) {
    const TriangleMesh q = make_quad(f[0], f[1], f[2]);
    const uint32_t base = uint32_t(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), q.positions.begin(), q.positions.end());
    mesh.normals.insert(mesh.normals.end(), q.normals.begin(), q.normals.end());
    mesh.uvs.insert(mesh.uvs.end(), q.uvs.begin(), q.uvs.end());
    for (uint32_t i : q.indices) mesh.indices.push_back(base + i);
  }
  return mesh;
}

TriangleMesh make_disk(Vec3 center, Vec3 normal, float radius, int segments) {
  const Frame frame = Frame::from_z(normalize(normal));
  TriangleMesh mesh;
  mesh.positions.push_back(center);
  mesh.normals.push_back(frame.n);
  mesh.uvs.push_back({0.5f, 0.5f});
  for (int j = 0; j < segments; ++j) {
    const float phi = 2.f * kPi * float(j) / float(segments);
    const float c = std::cos(phi), s = std::sin(phi);
    mesh.positions.push_back(center + radius * (c * frame.s + s * frame.t));
    mesh.normals.push_back(frame.n);
    mesh.uvs.push_back({0.5f + 0.5f * c, 0.5f + 0.5f * s});
  }
  // Frame is right-handed (s x t = n), so increasing phi winds CCW about n.
  for (int j = 0; j < segments; ++j)
    mesh.indices.insert(mesh.indices.end(), {0u, uint32_t(1 + j), uint32_t(1 + (j + 1) % segments)});
  return mesh;
}

TriangleMesh make_uv_sphere(Vec3 center, float radius, int rings, int segments) {
  TriangleMesh mesh;
  const int cols = segments + 1;  // the seam column is duplicated so uvs do not wrap
  for (int i = 0; i <= rings; ++i) {
    const float theta = kPi * float(i) / float(rings);
    // Exact poles so every pole vertex has the same position (is_closed welds by position).
    const float sin_t = (i == 0 || i == rings) ? 0.f : std::sin(theta);
    const float cos_t = i == 0 ? 1.f : (i == rings ? -1.f : std::cos(theta));
    for (int j = 0; j <= segments; ++j) {
      const float phi = 2.f * kPi * float(j % segments) / float(segments);  // seam: bit-identical to j = 0
      const Vec3 n{sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
      mesh.positions.push_back(center + radius * n);
      mesh.normals.push_back(n);
      mesh.uvs.push_back({float(j) / float(segments), float(i) / float(rings)});
    }
  }
  // (theta, phi, r) is right-handed, so (v00, v10, v11) winds CCW seen from outside.
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t v00 = i * cols + j, v01 = v00 + 1, v10 = v00 + cols, v11 = v10 + 1;
      if (i != 0) mesh.indices.insert(mesh.indices.end(), {v00, v11, v01});        // not at the north pole
      if (i != rings - 1) mesh.indices.insert(mesh.indices.end(), {v00, v10, v11});  // not at the south pole
    }
  return mesh;
}

bool is_closed(const TriangleMesh& mesh) {
  if (mesh.indices.empty()) return false;
  // Weld vertices by exact position (+0 and -0 alike) so flat-shaded meshes,
  // which split vertices along creases, are judged by their geometry.
  struct Key {
    std::array<uint32_t, 3> bits;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return std::hash<uint64_t>()((uint64_t(k.bits[0]) << 32 | k.bits[1]) ^ (uint64_t(k.bits[2]) * 0x9e3779b97f4a7c15ULL));
    }
  };
  std::unordered_map<Key, uint32_t, KeyHash> weld;
  std::vector<uint32_t> id(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    Key k;
    for (int a = 0; a < 3; ++a) {
      const float c = mesh.positions[v][a] + 0.f;  // -0 + 0 = +0
      std::memcpy(&k.bits[a], &c, sizeof(float));
    }
    id[v] = weld.emplace(k, uint32_t(weld.size())).first->second;
  }
  // Per undirected edge: how often it is traversed low->high and high->low.
  std::unordered_map<uint64_t, std::array<int, 2>> edges;
  for (int t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = id[mesh.indices[3 * t + k]], b = id[mesh.indices[3 * t + (k + 1) % 3]];
      if (a == b) return false;  // collapsed edge: not a proper surface
      const uint64_t key = uint64_t(std::min(a, b)) << 32 | std::max(a, b);
      ++edges[key][a < b ? 0 : 1];
    }
  for (const auto& [key, count] : edges)
    if (count[0] != 1 || count[1] != 1) return false;
  return true;
}

float triangle_area(const TriangleMesh& mesh, int triangle) { return 0.5f * length(triangle_cross(mesh, triangle)); }

float mesh_area(const TriangleMesh& mesh) {
  double sum = 0;
  for (int t = 0; t < mesh.triangle_count(); ++t) sum += triangle_area(mesh, t);
  return float(sum);
}

TriangleMesh transform_mesh(TriangleMesh mesh, const Transform& world_from_object) {
  for (Vec3& p : mesh.positions) p = world_from_object.point(p);
  for (Vec3& n : mesh.normals) n = normalize(world_from_object.normal(n));
  const Vec3 c0 = world_from_object.vector({1, 0, 0}), c1 = world_from_object.vector({0, 1, 0}),
             c2 = world_from_object.vector({0, 0, 1});
  if (dot(cross(c0, c1), c2) < 0.f)  // mirroring: keep cross(p1-p0, p2-p0) on the normals' side
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
  return mesh;
}

}  // namespace chlorovdb
