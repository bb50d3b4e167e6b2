// `chlorovdb info FILE.vdb`: every grid with its type, transform, bounds,
// value range, memory, and warnings about values a concentration cannot hold.
#include <fmt/format.h>

#include "cli/commands.h"
#include "grids/vdb_file.h"

namespace chlorovdb::cli {

namespace {

int info(const std::filesystem::path& vdb_file) {
  const GridReport report = inspect_vdb(vdb_file);
  fmt::print("{}: {} grid{}\n", report.file, report.grids.size(), report.grids.size() == 1 ? "" : "s");
  int warnings = 0;
  for (const GridInfo& g : report.grids) {
    fmt::print("\n{} ({}, {})\n", g.name, g.type, g.grid_class);
    // Lengths are in the grid's own unit: its length_unit metadata, metres by default.
    std::string u = "m";
    for (const auto& [key, value] : g.metadata)
      if (key == "length_unit") u = value;
    fmt::print("  voxel size      {:.6g} x {:.6g} x {:.6g} {}{}\n", g.voxel_size.x, g.voxel_size.y, g.voxel_size.z, u,
               g.linear_transform ? "" : " (non-linear transform: not usable as a medium)");
    const auto& m = g.world_from_index;
    fmt::print("  world_from_index [{:.6g} {:.6g} {:.6g} {:.6g}; {:.6g} {:.6g} {:.6g} {:.6g}; {:.6g} {:.6g} {:.6g} {:.6g}]\n",
               m[0][0], m[0][1], m[0][2], m[0][3], m[1][0], m[1][1], m[1][2], m[1][3], m[2][0], m[2][1], m[2][2],
               m[2][3]);
    if (g.active_index_bounds) {
      const auto& [lo, hi] = *g.active_index_bounds;
      fmt::print("  active voxels   {} in index [{}, {}, {}]..[{}, {}, {}]\n", g.active_voxels, lo[0], lo[1], lo[2],
                 hi[0], hi[1], hi[2]);
      const Bounds3& w = g.active_world_bounds;
      fmt::print("  world bounds    [{:.6g}, {:.6g}, {:.6g}]..[{:.6g}, {:.6g}, {:.6g}] {} (active voxels' cells)\n",
                 w.lo.x, w.lo.y, w.lo.z, w.hi.x, w.hi.y, w.hi.z, u);
    }
    if (g.stored_index_bounds) {
      const auto& [lo, hi] = *g.stored_index_bounds;
      fmt::print("  stored voxels   index [{}, {}, {}]..[{}, {}, {}] (active and leaf voxels: what the renderer loads)\n",
                 lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
      for (const Interpolation i : {Interpolation::nearest, Interpolation::trilinear}) {
        const Bounds3& w = g.medium_world_bounds[int(i)];
        fmt::print("  medium box      [{:.6g}, {:.6g}, {:.6g}]..[{:.6g}, {:.6g}, {:.6g}] {} ({}: where rendering sees the grid)\n",
                   w.lo.x, w.lo.y, w.lo.z, w.hi.x, w.hi.y, w.hi.z, u,
                   i == Interpolation::trilinear ? "trilinear" : "nearest");
      }
    }
    if (!g.active_index_bounds) {
      fmt::print("  active voxels   0 (empty grid)\n");
    }
    if (g.value_range) fmt::print("  value range     [{:.6g}, {:.6g}]\n", g.value_range->first, g.value_range->second);
    fmt::print("  memory          {:.3f} MiB\n", g.memory_bytes / 1048576.0);
    for (const auto& [key, value] : g.metadata) fmt::print("  {:<15} {}\n", key, value);
    if (g.invalid.nan) fmt::print("  warning: {} NaN values\n", g.invalid.nan), ++warnings;
    if (g.invalid.inf) fmt::print("  warning: {} infinite values\n", g.invalid.inf), ++warnings;
    if (g.invalid.negative)
      fmt::print("  warning: {} negative values (a concentration cannot be negative)\n", g.invalid.negative), ++warnings;
  }
  return warnings > 0 ? 2 : 0;
}

}  // namespace

Command add_info_command(CLI::App& app) {
  auto file = std::make_shared<std::filesystem::path>();
  CLI::App* sub = app.add_subcommand("info", "List the grids of a .vdb file and check their values");
  sub->add_option("file", *file, ".vdb file")->required();
  return {sub, [file] { return info(*file); }};
}

}  // namespace chlorovdb::cli
