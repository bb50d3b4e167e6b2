// libFuzzer target: the scene loader (scene/scene_loader.h). Bytes -> a
// temporary scene.json -> load_scene. InputError is the expected outcome for
// bad input; any other exception, a crash, a sanitizer report or a time-out is
// a bug. Beside the scene file lie a valid spectrum table (a.csv), a 4^3
// concentration grid (g.vdb, grid "density") and a closed mesh (m.obj), so
// inputs can reach the CSV, grid and mesh paths (fuzz/scene.dict names them).
#include <cstdint>
#include <fstream>

#include "fuzz_common.h"
#include "grids/vdb_file.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

void write_side_files() {
  const auto& dir = fuzz::scratch_dir();
  std::ofstream(dir / "a.csv") << "# test table\nwavelength_nm,value,b\n300,0.5,1\n500,1,2\n700,0.25,3\n";
  std::ofstream(dir / "m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  DenseGrid grid({4, 4, 4}, 1.f);
  grid.world_from_index = Transform::scale(Vec3(0.25f));
  grid.metadata.name = "density";
  grid.metadata.unit = "uM";
  grid.at(1, 2, 3) = 7.f;
  write_concentration_grid(dir / "g.vdb", grid);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::use_one_thread();
  write_side_files();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("scene.json", data, size);
  return fuzz::run_expecting_input_errors("load_scene", [&] {
    const Scene scene = load_scene(path);
    (void)scene;
  });
}
