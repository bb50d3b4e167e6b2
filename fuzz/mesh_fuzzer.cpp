// libFuzzer target: mesh and height-field files (geometry/mesh.h, voxelize/voxelize.h).
// The first byte of an input picks the file type, the rest is the file:
//   'o' .obj   'p' .ply   's' .stl   'g' .gltf   'b' .glb   'h' .hf (text height field)   'm' .pgm
// (any other byte: that byte modulo 7 in this order), so one target covers every format
// load_mesh and load_height_field read, and a mutated first byte hands the same bytes to
// another reader. A mesh that loads must be well formed (finite positions, indices in
// range, one unit normal / uv per position or none) and is then voxelized at about six
// voxels across its bounding box as a filled solid, a thin shell or a spill (puddle),
// picked by the input's length modulo 3 (one conversion per input: each costs ~0.15 s
// of OpenVDB under ASan); a height field as a spill. A 64 MiB memory limit keeps each conversion small: larger
// estimates must be refused. InputError is the expected outcome of bad input; anything
// else (another exception, a crash, a sanitizer report, a time-out) is a bug.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_common.h"
#include "geometry/mesh.h"
#include "voxelize/voxelize.h"

using namespace chlorovdb;

namespace {

constexpr std::array<const char*, 7> kExtensions{".obj", ".ply", ".stl", ".gltf", ".glb", ".hf", ".pgm"};
constexpr std::array<char, 7> kTags{'o', 'p', 's', 'g', 'b', 'h', 'm'};
constexpr int64_t kMemoryLimit = int64_t(64) << 20;

size_t format_of(uint8_t tag) {
  for (size_t i = 0; i < kTags.size(); ++i)
    if (tag == uint8_t(kTags[i])) return i;
  return tag % kTags.size();
}

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "\nfuzz_mesh: %s\n", what);
  std::abort();
}

void check_well_formed(const TriangleMesh& mesh) {
  if (mesh.indices.empty() || mesh.indices.size() % 3 != 0) fail("a loaded mesh has no whole triangles");
  for (const uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) fail("a loaded mesh has an index out of range");
  for (const Vec3& p : mesh.positions)
    if (!is_finite(p)) fail("a loaded mesh has a non-finite position");
  if (!mesh.normals.empty()) {
    if (mesh.normals.size() != mesh.positions.size()) fail("a loaded mesh has normals for some positions only");
    for (const Vec3& n : mesh.normals)
      if (!(std::abs(length(n) - 1.f) < 1e-3f)) fail("a loaded mesh has a shading normal that is not unit length");
  }
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size()) fail("a loaded mesh has uvs for some positions only");
}

VoxelizeOptions tiny_options(VoxelizeMode mode, const std::string& source, float voxel) {
  VoxelizeOptions o;
  o.mode = mode;
  o.voxel_size = Vec3(voxel);
  o.thickness = voxel;
  o.depth = 2.f * voxel;
  o.source_name = source;
  o.memory_limit_bytes = kMemoryLimit;
  return o;
}

void voxelize_tiny(const TriangleMesh& mesh, VoxelizeMode mode, const std::string& source) {
  const Vec3 extent = detail::mesh_bounds(mesh).diagonal();
  const float voxel = std::max({extent.x, extent.y, extent.z}) / 6.f;
  fuzz::run_expecting_input_errors("voxelize_mesh", [&] {
    const VoxelizeReport report =
        voxelize_mesh(mesh, tiny_options(mode, source, voxel), fuzz::scratch_dir() / "out.vdb");
    if (!(report.active_voxels > 0 && std::isfinite(report.amount) && report.amount > 0.0))
      fail("voxelize_mesh wrote an empty or non-finite grid without an error");
  });
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::use_one_thread();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t format = format_of(data[0]);
  const auto path = fuzz::write_input(std::string("input") + kExtensions[format], data + 1, size - 1);
  if (is_height_field_file(path)) {
    fuzz::run_expecting_input_errors("voxelize_height_field", [&] {
      const HeightField field = load_height_field(path);
      if (field.values.size() != size_t(field.nx) * size_t(field.nz)) fail("a height field's size does not match");
      VoxelizeOptions o = tiny_options(VoxelizeMode::spill, path.string(), 1.f);
      voxelize_height_field(field, o, fuzz::scratch_dir() / "out.vdb");
    });
    return 0;
  }
  fuzz::run_expecting_input_errors("load_mesh", [&] {
    const TriangleMesh mesh = load_mesh(path);
    check_well_formed(mesh);
    constexpr VoxelizeMode kModes[] = {VoxelizeMode::solid, VoxelizeMode::shell, VoxelizeMode::spill};
    voxelize_tiny(mesh, kModes[size % 3], path.string());
  });
  return 0;
}
