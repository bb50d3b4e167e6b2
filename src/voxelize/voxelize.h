#pragma once
// Meshes and height fields to concentration grids (.vdb fog volumes): the
// library behind `chlorovdb voxelize`. OpenVDB stays inside voxelize.cpp.
//
// Modes
//   solid  a closed mesh becomes a filled body (the liquid inside a glass).
//   shell  an open or thin mesh (a leaf) becomes a shell of `thickness`, centred on the surface;
//          around a free boundary edge the shell is rounded (distance to the edge).
//   spill  a footprint mesh is extruded by `depth` into a closed prism and filled; or a height
//          field (load_height_field) gives the local depth of a layer on the plane y = 0.
//
// Method (meshes). OpenVDB's meshToVolume runs in the grid's index space, where every voxel is a
// unit cube: the mesh is divided by the voxel size per axis first, so `voxel_size` may differ per
// axis (a 0.2 mm leaf blade lying in the xz plane can have 20 µm voxels along y only). It gives the
// narrow-band topology, the inside/outside sign (a flood fill, unchanged by the axis scaling) and,
// per band voxel, the closest triangle in index space. Index-space distances are not world
// distances when the voxels are not cubes, so every band voxel's distance is recomputed in world
// units (metres) as an exact point-triangle distance: starting from the index-closest triangles
// of the voxel (near the surface, also of its 26 neighbours), then walking across edges and
// vertices to any neighbouring triangle that is closer in world units, until none is. This is
// exact wherever the world-closest triangle is reachable that way: always on convex parts and
// flat or gently curved sheets; tests check thickness across a tilted shell with 5:1 voxels.
// The band is made wide enough in index voxels to hold every voxel within the needed world
// distance (index distance <= world distance / smallest voxel size).
//
// Values. A voxel holds C(x) · coverage, the part of the voxel inside the body, estimated with a
// box filter along the distance gradient g: with w = Σ|g_i| h_i the voxel's world extent along g,
// coverage = clamp(1/2 - s/w, 0, 1) at signed distance s (solid, spill), or the overlap of
// [u - w/2, u + w/2] with [-t/2, t/2] over w for a shell of thickness t at unsigned distance u.
// This is exact for planes at any orientation and offset, so the summed values give the body's
// volume (tests: a sphere and a cube within 1 %) and a shell thinner than a voxel keeps its amount
// of pigment. Near feature edges (boundary edges, and edges where faces meet at over ~10°) one
// filter is off: a voxel centred on a box edge would count half instead of a quarter, a shell's
// rounded rim would count as a slab. There the voxel is split into 3 x 3 x 3 sub-voxels, each
// filtered along its own gradient (signs from angle-weighted pseudo-normals), which confines the
// error to the sub-voxels on the edge: 9 times smaller.
// Values are in `unit` (metadata "unit", "scale" = 1, "provenance" = the command line).
// The grid's voxel (i, j, k) is centred at world (i·hx, j·hy, k·hz).
//
// Cost. The voxel count and memory are estimated from the mesh before anything large is
// allocated; a count over 2^31 or memory over what the machine has available is refused with an
// InputError stating both.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/memory.h"
#include "core/transform.h"
#include "core/vec.h"
#include "geometry/mesh.h"
#include "grids/voxel_grid.h"
#include "voxelize/profile.h"

namespace chlorovdb {

enum class VoxelizeMode { solid, shell, spill };
enum class SpillDirection {
  normal,  // along the footprint's area-weighted normal (its winding picks the side)
  up,      // along +y
};

struct VoxelizeOptions {
  VoxelizeMode mode = VoxelizeMode::solid;
  Vec3 voxel_size{0.f};            // metres per voxel along world x, y, z
  float thickness = 0.f;           // shell: full thickness, centred on the surface, metres
  float depth = 0.f;               // spill: layer depth, metres (height field: local depth = sample × depth)
  SpillDirection spill_direction = SpillDirection::normal;
  float height_field_cell = 0.f;   // height field: metres between samples in x and z (0: voxel_size.x)
  Transform world_from_input;      // applied to the mesh / height field first (e.g. scale mm -> m)
  ConcentrationProfile profile;
  std::string unit = "uM";         // unit of the stored values: M, mM, uM (µM) or nM
  std::string grid_name = "density";
  std::string source_name;         // input named in errors and provenance (voxelize_file sets the path)
  std::string command;             // recorded as provenance; empty: rebuilt from these options
  int64_t memory_limit_bytes = 0;  // refuse above this; 0: MemAvailable of /proc/meminfo
};

// What a conversion will cost, estimated from the geometry before allocating.
struct VoxelEstimate {
  double body_voxels = 0;     // voxels the body fills (interior included)
  double band_voxels = 0;     // voxels of the narrow band the distance computation touches
  double stored_voxels = 0;   // voxels stored one by one in the output (the rest are constant tiles)
  double bytes = 0;           // peak memory of the conversion
  int64_t available_bytes = 0;  // the limit compared against (MemAvailable or memory_limit_bytes; 0: unknown)
  double voxels() const { return body_voxels > band_voxels ? body_voxels : band_voxels; }
};

// What was written.
struct VoxelizeReport {
  VoxelEstimate estimate;
  int64_t active_voxels = 0;     // voxels with a value > 0 (constant tiles counted voxel by voxel)
  double filled_volume = 0;      // Σ coverage × voxel volume, m³
  double amount = 0;             // Σ value × voxel volume, unit · m³
  float min_value = 0, max_value = 0;  // over active voxels
  Coord index_lo{0, 0, 0}, index_hi{-1, -1, -1};  // inclusive box of the active voxels
  int64_t unresolved_voxels = 0;  // band voxels without a closest triangle nearby (OpenVDB's distance used; expect 0)
  std::string provenance;
};

// A height field: one sample per (x, z) cell of a regular grid, the relative local depth of a layer.
struct HeightField {
  int nx = 0, nz = 0;         // samples along x (columns) and z (rows)
  std::vector<float> values;  // values[i + nx * j] >= 0, sample i along x, j along z
  float at(int i, int j) const { return values[size_t(i) + size_t(nx) * size_t(j)]; }
};

inline constexpr double kMaxVoxels = 2147483648.0;  // 2^31: refused regardless of memory

// Voxelizes the mesh (coordinates before options.world_from_input) and writes one float grid to `output`.
VoxelizeReport voxelize_mesh(const TriangleMesh& mesh, const VoxelizeOptions& options,
                             const std::filesystem::path& output);
// Voxelizes a height field (spill mode only) and writes one float grid to `output`.
VoxelizeReport voxelize_height_field(const HeightField& field, const VoxelizeOptions& options,
                                     const std::filesystem::path& output);
// Loads `input` (a height field if is_height_field_file, else a mesh through load_mesh) and voxelizes it.
VoxelizeReport voxelize_file(const std::filesystem::path& input, VoxelizeOptions options,
                             const std::filesystem::path& output);

// Height field files: ".pgm" (P2 or P5 greymap, sample = grey / maxval, seen from +y with +x to the
// right and +z down), or ".hf" / ".txt" / ".csv" text (one row per z, numbers split by spaces or
// commas, `#` lines ignored). Throws InputError naming the file, line and value.
HeightField load_height_field(const std::filesystem::path& file);
bool is_height_field_file(const std::filesystem::path& file);

// The closed prism a spill footprint sweeps when moved by `offset` (welded by position; footprint
// flipped first if its normal points against `offset`). Throws InputError naming `source` if the
// footprint is not a consistently oriented surface or lies (nearly) parallel to `offset`.
TriangleMesh extrude_footprint(const TriangleMesh& footprint, const Vec3& offset, std::string_view source);
// The spill offset: depth × (footprint normal or +y) for `options`.
Vec3 spill_offset(const TriangleMesh& footprint, const VoxelizeOptions& options);

// Cost estimate of voxelizing `world_mesh` (already in world space; for spills the extruded prism).
VoxelEstimate estimate_voxels(const TriangleMesh& world_mesh, const VoxelizeOptions& options,
                              const ProfileSampler& profile);
// Throws InputError (naming options.source_name, the voxel size, the estimate and the memory
// available) if the estimate exceeds kMaxVoxels or the memory available.
void check_estimate(const VoxelEstimate& estimate, const VoxelizeOptions& options);
// Throws InputError (naming options.source_name and the voxel size) if `world_body` grown by
// `margin_voxels` reaches beyond ±kMaxVoxelIndex voxels from the origin on an axis: the
// renderer refuses such grids, and the conversion's integer indices would overflow.
void check_index_range(const Bounds3& world_body, double margin_voxels, const VoxelizeOptions& options);

// Throws InputError for a voxel size that is not positive and finite, or mode parameters out of range.
void validate_options(const VoxelizeOptions& options);
// The equivalent command line (mode, sizes, profile, unit), for provenance.
std::string describe_options(const VoxelizeOptions& options, const ProfileSampler& profile);

std::string_view to_string(VoxelizeMode mode);
bool parse_voxelize_mode(std::string_view word, VoxelizeMode* mode);
std::string_view to_string(SpillDirection direction);
bool parse_spill_direction(std::string_view word, SpillDirection* direction);  // "normal" | "up"

namespace detail {

// Narrow band half widths in index voxels handed to meshToVolume.
struct BandWidths {
  float exterior = 0, interior = 0;
};
// Wide enough to hold every voxel within `depth_needed` metres inside (falloff), within the
// shell, and every partly covered voxel (centre within its half-diagonal of the surface) plus one voxel.
BandWidths band_widths(const VoxelizeOptions& options, float depth_needed);
// Σ triangle areas after dividing coordinates by the voxel size (in voxel faces).
double index_space_area(const TriangleMesh& mesh, const Vec3& voxel_size);
// Signed volume enclosed by a closed mesh (positive for outward winding), m³.
double enclosed_volume(const TriangleMesh& mesh);
// Mesh bounding box.
Bounds3 mesh_bounds(const TriangleMesh& mesh);

}  // namespace detail

}  // namespace chlorovdb
