// `chlorovdb voxelize`: meshes and height fields to concentration grids
// (the options and the work live in src/voxelize/).
#include "cli/commands.h"
#include "voxelize/voxelize_command.h"

namespace chlorovdb::cli {

Command add_voxelize_command(CLI::App& app) {
  auto args = std::make_shared<VoxelizeArgs>();
  add_voxelize_subcommand(app, *args);
  return {app.get_subcommands({}).back(), [args] { return voxelize(*args); }};
}

}  // namespace chlorovdb::cli
