#pragma once
// `chlorovdb voxelize MESH -o OUT.vdb --voxel-size V [...]`: arguments as given on the
// command line, the command itself, and its CLI11 wiring (CLI11 stays in the .cpp).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "voxelize/voxelize.h"

namespace CLI {
class App;
}

namespace chlorovdb::cli {

struct VoxelizeArgs {
  std::filesystem::path input;           // mesh (anything Assimp reads) or height field (.pgm .hf .txt .csv)
  std::filesystem::path output;          // .vdb
  std::string mode = "solid";            // solid | shell | spill
  std::string voxel_size;                // metres: "V" or "vx,vy,vz"
  std::optional<float> thickness;        // shell, metres
  std::optional<float> depth;            // spill, metres
  std::string direction = "normal";      // spill: normal | up
  std::optional<float> cell_size;        // height field sample spacing, metres
  std::optional<float> concentration;    // C in `unit` (default 1)
  std::string unit = "uM";
  std::string profile = "uniform";       // uniform | linear | noise | falloff | grid
  std::string gradient;                  // linear: "C0,C1"
  std::string axis = "y";                // linear: x | y | z
  uint64_t noise_seed = 1;
  float noise_scale = 0.f;               // metres; 0: a quarter of the body's size
  float noise_amplitude = 0.5f;
  int noise_octaves = 3;
  std::optional<float> falloff_length;   // metres
  std::string falloff_shape = "decay";   // decay | rise
  std::filesystem::path source_grid;     // grid profile: .vdb
  std::string source_grid_name = "density";
  std::string grid_name = "density";     // output grid name
  float scale = 1.f;                     // input units -> metres (e.g. 0.001 for a mesh in mm)
  std::string translate;                 // "x,y,z" metres, applied after the scale
  bool quiet = false;
};

// The library options for `args` (flags parsed and checked; InputError names the flag), with the
// command line they amount to as provenance.
VoxelizeOptions voxelize_options(const VoxelizeArgs& args);
// The command line that `args` amount to (every effective option), as recorded in the grid.
std::string voxelize_command_line(const VoxelizeArgs& args);
// Runs the conversion and prints what was written (unless quiet). Returns the exit code;
// throws InputError for bad input (main prints it).
int voxelize(const VoxelizeArgs& args);
// Adds the "voxelize" subcommand with every option bound to `args` (which must outlive `app`).
void add_voxelize_subcommand(CLI::App& app, VoxelizeArgs& args);

}  // namespace chlorovdb::cli
