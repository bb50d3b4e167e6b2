// Spill inputs: footprint meshes swept into closed prisms, and height field files.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include <fmt/format.h>

#include "core/error.h"
#include "voxelize/voxelize.h"

namespace chlorovdb {
namespace {

// Area-weighted normal (length = projected area along it).
Vec3 area_normal(const TriangleMesh& mesh) {
  Vec3 sum(0.f);
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
               c = mesh.positions[mesh.indices[3 * t + 2]];
    sum += 0.5f * cross(b - a, c - a);
  }
  return sum;
}

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

void check_sample(float v, const std::string& file, const std::string& where, std::string_view text) {
  if (!std::isfinite(v) || v < 0.f)
    throw InputError(file, where, text, "a height field sample must be a finite number >= 0");
}

HeightField load_text_height_field(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(file, "", "", "cannot open the height field");
  HeightField field;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream tokens(line);
    std::string token;
    int count = 0;
    while (tokens >> token) {
      float v = 0.f;
      const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
      const std::string where = fmt::format("line {}, column {}", line_no, count + 1);
      if (ec != std::errc() || end != token.data() + token.size())
        throw InputError(file, where, token, "not a number");
      check_sample(v, file, where, token);
      field.values.push_back(v);
      ++count;
    }
    if (field.nz == 0) field.nx = count;
    else if (count != field.nx)
      throw InputError(file, fmt::format("line {}", line_no), fmt::format("{} samples", count),
                       fmt::format("every row needs the same number of samples as the first ({})", field.nx));
    ++field.nz;
  }
  return field;
}

// Netpbm greymap: "P2" (ASCII) or "P5" (binary, 1 or 2 bytes per sample, big-endian), '#' comments in the header.
HeightField load_pgm_height_field(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, "", "", "cannot open the height field");
  auto header_token = [&]() {
    std::string token;
    for (int c = in.get(); c != EOF; c = in.get()) {
      if (c == '#') {
        while (c != EOF && c != '\n') c = in.get();
        if (!token.empty()) break;
        continue;
      }
      if (std::isspace(c)) {
        if (!token.empty()) break;
        continue;
      }
      token += char(c);
    }
    return token;
  };
  auto header_int = [&](const char* what) {
    const std::string token = header_token();
    int v = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || end != token.data() + token.size() || v <= 0)
      throw InputError(file, fmt::format("PGM header {}", what), token, "must be a positive integer");
    return v;
  };
  const std::string magic = header_token();
  if (magic != "P2" && magic != "P5")
    throw InputError(file, "PGM header", magic.substr(0, 8), "not a PGM greymap (expected P2 or P5)");
  HeightField field;
  field.nx = header_int("width");
  field.nz = header_int("height");
  const int maxval = header_int("maxval");
  if (maxval > 65535) throw InputError(file, "PGM header maxval", fmt::format("{}", maxval), "must be <= 65535");
  if (int64_t(field.nx) * field.nz > (int64_t(1) << 28))
    throw InputError(file, "PGM header", fmt::format("{}x{}", field.nx, field.nz), "too many samples");
  const size_t n = size_t(field.nx) * size_t(field.nz);
  field.values.resize(n);
  for (size_t i = 0; i < n; ++i) {
    int v = 0;
    if (magic == "P2") {
      const std::string token = header_token();
      const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
      if (token.empty() || ec != std::errc() || end != token.data() + token.size())
        throw InputError(file, fmt::format("sample {}", i), token.empty() ? "(end of file)" : token,
                         fmt::format("expected {} samples", n));
    } else {
      const int hi = in.get();
      const int lo = maxval > 255 ? in.get() : 0;
      if (hi == EOF || lo == EOF)
        throw InputError(file, fmt::format("sample {}", i), "(end of file)", fmt::format("expected {} samples", n));
      v = maxval > 255 ? (hi << 8 | lo) : hi;
    }
    if (v > maxval)
      throw InputError(file, fmt::format("sample {}", i), fmt::format("{}", v), fmt::format("exceeds maxval {}", maxval));
    field.values[i] = float(v) / float(maxval);
  }
  return field;
}

}  // namespace

bool is_height_field_file(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  return ext == ".pgm" || ext == ".hf" || ext == ".txt" || ext == ".csv";
}

HeightField load_height_field(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(file, "", "", "height field file not found");
  HeightField field = lower_extension(path) == ".pgm" ? load_pgm_height_field(path) : load_text_height_field(path);
  if (field.nx < 2 || field.nz < 2)
    throw InputError(file, "", fmt::format("{}x{} samples", field.nx, field.nz),
                     "a height field needs at least 2x2 samples");
  if (std::none_of(field.values.begin(), field.values.end(), [](float v) { return v > 0.f; }))
    throw InputError(file, "", "", "every sample is 0: the height field holds no liquid");
  return field;
}

Vec3 spill_offset(const TriangleMesh& footprint, const VoxelizeOptions& o) {
  if (o.spill_direction == SpillDirection::up) return {0.f, o.depth, 0.f};
  const Vec3 n = area_normal(footprint);
  const float area = mesh_area(footprint);
  // A planar footprint's normal sum has the length of its area; a crumpled one's is shorter.
  if (!(length(n) >= 0.5f * area))
    throw InputError(o.source_name.empty() ? "<mesh>" : o.source_name, "--direction", "normal",
                     fmt::format("the footprint is not planar enough to have one normal (its area-weighted normal is "
                                 "{:.0f} % of its area); use --direction up",
                                 100.f * length(n) / area));
  return normalize(n) * o.depth;
}

TriangleMesh extrude_footprint(const TriangleMesh& footprint, const Vec3& offset, std::string_view source) {
  // Weld by exact position so split normals / uvs do not cut the footprint into pieces.
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
  std::vector<Vec3> points;
  std::vector<uint32_t> id(footprint.positions.size());
  for (size_t v = 0; v < footprint.positions.size(); ++v) {
    Key k;
    for (int a = 0; a < 3; ++a) {
      const float c = footprint.positions[v][a] + 0.f;  // -0 + 0 = +0
      std::memcpy(&k.bits[a], &c, sizeof(float));
    }
    const auto [it, inserted] = weld.emplace(k, uint32_t(points.size()));
    if (inserted) points.push_back(footprint.positions[v]);
    id[v] = it->second;
  }
  const Vec3 n = area_normal(footprint);
  const float area = mesh_area(footprint);
  const float along = dot(n, normalize(offset));
  if (!(std::abs(along) >= 0.1f * area))
    throw InputError(source, "--direction", "",
                     fmt::format("the footprint lies (nearly) parallel to the extrusion direction ({:.3g}, {:.3g}, "
                                 "{:.3g}): its projected area is {:.0f} % of its area",
                                 offset.x, offset.y, offset.z, 100.f * std::abs(along) / area));
  const bool flip = along < 0.f;

  std::vector<std::array<uint32_t, 3>> tris;
  for (int t = 0; t < footprint.triangle_count(); ++t) {
    std::array<uint32_t, 3> tri{id[footprint.indices[3 * t]], id[footprint.indices[3 * t + 1]],
                                id[footprint.indices[3 * t + 2]]};
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    if (flip) std::swap(tri[1], tri[2]);
    tris.push_back(tri);
  }
  // Directed edges: a consistently oriented manifold footprint uses each one at most once.
  std::unordered_map<uint64_t, int> directed;
  for (const auto& tri : tris)
    for (int k = 0; k < 3; ++k) {
      const uint64_t key = uint64_t(tri[k]) << 32 | tri[(k + 1) % 3];
      if (++directed[key] > 1) {
        const Vec3 a = points[tri[k]], b = points[tri[(k + 1) % 3]];
        throw InputError(source, "--mode", "spill",
                         fmt::format("the footprint is not a consistently oriented surface: the edge ({:.4g}, {:.4g}, "
                                     "{:.4g}) - ({:.4g}, {:.4g}, {:.4g}) is used twice in the same direction",
                                     a.x, a.y, a.z, b.x, b.y, b.z));
      }
    }

  TriangleMesh prism;
  const uint32_t m = uint32_t(points.size());
  prism.positions = points;
  for (const Vec3& p : points) prism.positions.push_back(p + offset);
  for (const auto& tri : tris) {
    prism.indices.insert(prism.indices.end(), {tri[0], tri[2], tri[1]});              // bottom faces -offset
    prism.indices.insert(prism.indices.end(), {tri[0] + m, tri[1] + m, tri[2] + m});  // top faces +offset
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[k], b = tri[(k + 1) % 3];
      if (directed.count(uint64_t(b) << 32 | a)) continue;  // interior edge
      // Boundary edge a->b runs counter-clockwise about the normal, so cross(b - a, offset) points out.
      prism.indices.insert(prism.indices.end(), {a, b, b + m});
      prism.indices.insert(prism.indices.end(), {a, b + m, a + m});
    }
  }
  return prism;
}

}  // namespace chlorovdb
