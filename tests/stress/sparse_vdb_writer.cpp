// Writes sparse .vdb files that write_concentration_grid (dense boxes) cannot
// make: a few active voxels far apart. The only OpenVDB include of tests/stress.
#include "sparse_vdb_writer.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

namespace chlorovdb::stress {

void write_sparse_grid(const std::filesystem::path& path, const std::vector<std::pair<Coord, float>>& voxels,
                       double voxel_size) {
  openvdb::initialize();
  auto grid = openvdb::FloatGrid::create(0.f);
  grid->setName("density");
  grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_size));
  auto accessor = grid->getAccessor();
  for (const auto& [c, v] : voxels) accessor.setValue(openvdb::Coord(c[0], c[1], c[2]), v);
  openvdb::io::File file(path.string());
  file.write({grid});
  file.close();
}

}  // namespace chlorovdb::stress
