#pragma once
// Reading, writing and describing .vdb files. The only interface to OpenVDB;
// its headers stay inside vdb_file.cpp (they cost 15-40 s per translation unit).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"
#include "grids/voxel_grid.h"

namespace chlorovdb {

struct GridLoadOptions {
  // NaN, infinite and negative voxel values are refused (InputError with their
  // counts) unless this is set: then they are clamped to 0 and counted in
  // VoxelGrid::metadata().clamped_voxels.
  bool clamp_invalid = false;
};

// Loads the float grid `grid_name` with its index-to-world transform (any
// affine map, non-uniform scale included, in the metadata's length unit) and
// its metadata "unit", "scale", "length_unit" and "provenance". A double grid is
// converted to float (metadata().converted_from says so). Throws InputError
// naming the file, the grid and the problem: missing file, unreadable file, no
// such grid (listing the grids there are), neither float nor double,
// non-linear (frustum) transform, invalid values.
VoxelGrid load_concentration_grid(const std::filesystem::path& path, std::string_view grid_name,
                                  GridLoadOptions options = {});

// Writes float grids (dense values -> sparse OpenVDB: voxels equal to the
// background stay inactive) with metadata unit, scale and provenance. Grid
// names come from each DenseGrid's metadata.name. Throws InputError if the file
// cannot be written.
void write_concentration_grids(const std::filesystem::path& path, std::span<const DenseGrid> grids);
inline void write_concentration_grid(const std::filesystem::path& path, const DenseGrid& grid) {
  write_concentration_grids(path, std::span<const DenseGrid>(&grid, 1));
}

// What `chlorovdb info` prints about one grid.
struct GridInfo {
  std::string name;
  std::string type;         // OpenVDB value type: "float", "double", "vec3s", ...
  std::string grid_class;   // "fog volume", "level set", "unknown", ...
  bool linear_transform = true;
  Transform::Mat world_from_index{};  // affine part of the transform (first-order approximation if not linear)
  Vec3 voxel_size;                    // world units per voxel along index x, y, z
  std::optional<std::pair<Coord, Coord>> active_index_bounds;  // inclusive voxel range; none if no active values
  Bounds3 active_world_bounds;        // world box around the active voxels' cells
  // Voxels a lookup can see differ from the background (active ones and every voxel
  // of a leaf node), as the renderer loads them; none if the grid is empty.
  std::optional<std::pair<Coord, Coord>> stored_index_bounds;
  // The box of a medium made of this grid, by Interpolation (VoxelGrid::world_bounds).
  Bounds3 medium_world_bounds[2];
  std::optional<std::pair<double, double>> value_range;  // of active values (scalar grids)
  int64_t active_voxels = 0;
  int64_t memory_bytes = 0;
  InvalidValueCounts invalid;         // over every stored value, active or not (scalar grids)
  std::vector<std::pair<std::string, std::string>> metadata;  // per-grid metadata as text
};

struct GridReport {
  std::string file;
  std::vector<GridInfo> grids;
};

// Reads every grid in the file. Throws InputError for missing / unreadable files.
GridReport inspect_vdb(const std::filesystem::path& path);

}  // namespace chlorovdb
