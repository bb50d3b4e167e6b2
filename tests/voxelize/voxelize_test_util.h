#pragma once
// Shared helpers of the voxelize tests: temporary files, OBJ writing and grid integrals.
// Grids are read back with load_concentration_grid, so the tests never include OpenVDB.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "core/error.h"
#include "geometry/mesh.h"
#include "grids/vdb_file.h"
#include "grids/voxel_grid.h"
#include "voxelize/voxelize.h"

namespace chlorovdb::test {

inline std::filesystem::path temp_path(const std::string& name) {
  return scratch_dir("test_voxelize") / name;
}

inline std::filesystem::path write_obj(const TriangleMesh& mesh, const std::string& name) {
  const auto path = temp_path(name);
  std::ofstream out(path);
  for (const Vec3& p : mesh.positions) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
  for (int t = 0; t < mesh.triangle_count(); ++t)
    out << "f " << mesh.indices[3 * t] + 1 << ' ' << mesh.indices[3 * t + 1] + 1 << ' ' << mesh.indices[3 * t + 2] + 1
        << '\n';
  return path;
}

inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

inline VoxelizeOptions options_with(VoxelizeMode mode, Vec3 voxel_size) {
  VoxelizeOptions o;
  o.mode = mode;
  o.voxel_size = voxel_size;
  return o;
}

// Σ value × voxel volume over the stored voxels (unit · m³); the grid is axis-aligned (scale only).
inline double integral(const VoxelGrid& g) {
  const auto& m = g.world_from_index().matrix();
  const double voxel_volume = double(m[0][0]) * m[1][1] * m[2][2];
  double sum = 0;
  const Coord lo = g.index_lo(), hi = g.index_hi();
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) sum += g.voxel(x, y, z);
  return sum * voxel_volume;
}

// Number of voxels whose value passes `keep`.
inline int64_t count_voxels(const VoxelGrid& g, const std::function<bool(float)>& keep) {
  int64_t n = 0;
  const Coord lo = g.index_lo(), hi = g.index_hi();
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) n += keep(g.voxel(x, y, z)) ? 1 : 0;
  return n;
}

// The voxel whose centre is nearest to world point p.
inline float voxel_at(const VoxelGrid& g, const Vec3& p) {
  const Vec3 q = g.index_from_world().point(p);
  return g.voxel(int(std::lround(q.x)), int(std::lround(q.y)), int(std::lround(q.z)));
}

// ∫ value dt along the world segment a -> b (trilinear, fine midpoint steps), unit · m.
inline double line_integral(const VoxelGrid& g, const Vec3& a, const Vec3& b, int steps = 4000) {
  double sum = 0;
  for (int i = 0; i < steps; ++i) {
    const Vec3 p = a + (b - a) * ((float(i) + 0.5f) / float(steps));
    sum += g.trilinear(g.index_from_world().point(p));
  }
  return sum * double(length(b - a)) / steps;
}

}  // namespace chlorovdb::test
