#pragma once
#include <filesystem>
#include <utility>
#include <vector>

#include "grids/voxel_grid.h"

namespace chlorovdb::stress {

// One float grid "density" with the given active voxels (index space), cubic voxels.
void write_sparse_grid(const std::filesystem::path& path, const std::vector<std::pair<Coord, float>>& voxels,
                       double voxel_size);

}  // namespace chlorovdb::stress
