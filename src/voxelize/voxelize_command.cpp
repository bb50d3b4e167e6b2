// `chlorovdb voxelize`: flags -> VoxelizeOptions -> voxelize_file, and the CLI11 wiring.
#include "voxelize/voxelize_command.h"

#include <charconv>
#include <cmath>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli/options.h"
#include "core/error.h"

namespace chlorovdb::cli {
namespace {

constexpr const char* kCommand = "chlorovdb voxelize";

// Comma-separated floats; InputError naming the flag otherwise.
std::vector<float> parse_floats(const std::string& text, const char* flag, const char* expected) {
  std::vector<float> values;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(',', start), text.size());
    const std::string token = text.substr(start, end - start);
    float v = 0.f;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (token.empty() || ec != std::errc() || ptr != token.data() + token.size() || !std::isfinite(v))
      throw InputError(kCommand, flag, text, expected);
    values.push_back(v);
    start = end + 1;
  }
  return values;
}

int parse_axis(const std::string& word) {
  if (word == "x") return 0;
  if (word == "y") return 1;
  if (word == "z") return 2;
  throw InputError(kCommand, "--axis", word, "must be x, y or z");
}

std::string format_volume(double m3) {
  if (m3 >= 1e-3) return fmt::format("{:.4g} L", m3 * 1e3);
  if (m3 >= 1e-6) return fmt::format("{:.4g} mL", m3 * 1e6);
  return fmt::format("{:.4g} µL", m3 * 1e9);
}

}  // namespace

VoxelizeOptions voxelize_options(const VoxelizeArgs& a) {
  VoxelizeOptions o;
  o.source_name = a.input.string();
  if (!parse_voxelize_mode(a.mode, &o.mode)) throw InputError(kCommand, "--mode", a.mode, "must be solid, shell or spill");
  if (a.voxel_size.empty()) throw InputError(kCommand, "--voxel-size", "", "is required (metres per voxel)");
  const std::vector<float> h =
      parse_floats(a.voxel_size, "--voxel-size", "expected one length or three (vx,vy,vz), in metres");
  if (h.size() == 1) o.voxel_size = Vec3(h[0]);
  else if (h.size() == 3) o.voxel_size = Vec3(h[0], h[1], h[2]);
  else throw InputError(kCommand, "--voxel-size", a.voxel_size, "expected one length or three (vx,vy,vz), in metres");

  if (a.thickness && o.mode != VoxelizeMode::shell)
    throw InputError(kCommand, "--thickness", fmt::format("{}", *a.thickness), "only applies to --mode shell");
  if (a.depth && o.mode != VoxelizeMode::spill)
    throw InputError(kCommand, "--depth", fmt::format("{}", *a.depth), "only applies to --mode spill");
  o.thickness = a.thickness.value_or(0.f);
  o.depth = a.depth.value_or(0.f);
  if (!parse_spill_direction(a.direction, &o.spill_direction))
    throw InputError(kCommand, "--direction", a.direction, "must be normal or up");
  o.height_field_cell = a.cell_size.value_or(0.f);

  ConcentrationProfile& p = o.profile;
  if (!parse_profile_kind(a.profile, &p.kind))
    throw InputError(kCommand, "--profile", a.profile, "must be uniform, linear, noise, falloff or grid");
  if (a.concentration && (p.kind == ProfileKind::linear || p.kind == ProfileKind::grid))
    throw InputError(kCommand, "--concentration", fmt::format("{}", *a.concentration),
                     p.kind == ProfileKind::linear ? "has no effect with --profile linear (give --gradient C0,C1)"
                                                   : "has no effect with --profile grid (values come from the grid)");
  p.concentration = a.concentration.value_or(1.f);
  if (p.kind == ProfileKind::linear) {
    if (a.gradient.empty()) throw InputError(kCommand, "--gradient", "", "--profile linear needs --gradient C0,C1");
    const std::vector<float> c = parse_floats(a.gradient, "--gradient", "expected two concentrations C0,C1");
    if (c.size() != 2) throw InputError(kCommand, "--gradient", a.gradient, "expected two concentrations C0,C1");
    p.c0 = c[0];
    p.c1 = c[1];
    p.axis = parse_axis(a.axis);
  }
  p.seed = a.noise_seed;
  p.noise_scale = a.noise_scale;
  p.noise_amplitude = a.noise_amplitude;
  p.noise_octaves = a.noise_octaves;
  if (p.kind == ProfileKind::falloff && !a.falloff_length)
    throw InputError(kCommand, "--falloff-length", "", "--profile falloff needs a length scale in metres");
  p.falloff_length = a.falloff_length.value_or(0.f);
  if (!parse_falloff_shape(a.falloff_shape, &p.falloff_shape))
    throw InputError(kCommand, "--falloff-shape", a.falloff_shape, "must be decay or rise");
  p.grid_file = a.source_grid;
  p.grid_name = a.source_grid_name;
  o.unit = a.unit;
  o.grid_name = a.grid_name;

  if (!(std::isfinite(a.scale) && a.scale > 0.f))
    throw InputError(kCommand, "--scale", fmt::format("{}", a.scale), "must be a positive factor (input units to metres)");
  Vec3 t(0.f);
  if (!a.translate.empty()) {
    const std::vector<float> v = parse_floats(a.translate, "--translate", "expected x,y,z in metres");
    if (v.size() != 3) throw InputError(kCommand, "--translate", a.translate, "expected x,y,z in metres");
    t = Vec3(v[0], v[1], v[2]);
  }
  if (a.scale != 1.f || !(t == Vec3(0.f))) o.world_from_input = Transform::translate(t) * Transform::scale(Vec3(a.scale));
  o.command = voxelize_command_line(a);
  return o;
}

std::string voxelize_command_line(const VoxelizeArgs& a) {
  std::string s = fmt::format("{} {} -o {} --mode {} --voxel-size {}", kCommand, a.input.string(), a.output.string(),
                              a.mode, a.voxel_size);
  if (a.thickness) s += fmt::format(" --thickness {}", *a.thickness);
  if (a.depth) s += fmt::format(" --depth {} --direction {}", *a.depth, a.direction);
  if (a.cell_size) s += fmt::format(" --cell-size {}", *a.cell_size);
  s += fmt::format(" --profile {}", a.profile);
  if (a.profile != "linear" && a.profile != "grid") s += fmt::format(" --concentration {}", a.concentration.value_or(1.f));
  if (a.profile == "linear") s += fmt::format(" --gradient {} --axis {}", a.gradient, a.axis);
  if (a.profile == "noise")
    s += fmt::format(" --noise-seed {} --noise-scale {} --noise-amplitude {} --noise-octaves {}", a.noise_seed,
                     a.noise_scale, a.noise_amplitude, a.noise_octaves);
  if (a.profile == "falloff")
    s += fmt::format(" --falloff-length {} --falloff-shape {}", a.falloff_length.value_or(0.f), a.falloff_shape);
  if (a.profile == "grid")
    s += fmt::format(" --source-grid {} --source-grid-name {}", a.source_grid.string(), a.source_grid_name);
  s += fmt::format(" --unit {} --grid-name {}", a.unit, a.grid_name);
  if (a.scale != 1.f) s += fmt::format(" --scale {}", a.scale);
  if (!a.translate.empty()) s += fmt::format(" --translate {}", a.translate);
  return s;
}

int voxelize(const VoxelizeArgs& args) {
  if (args.output.empty()) throw InputError(kCommand, "-o", "", "an output .vdb file is required");
  const VoxelizeOptions options = voxelize_options(args);
  const VoxelizeReport r = voxelize_file(args.input, options, args.output);
  if (!args.quiet) {
    const Vec3 h = options.voxel_size;
    fmt::print("wrote {}: grid \"{}\", {} active voxels of {} x {} x {} m, index box [{}, {}, {}] .. [{}, {}, {}]\n",
               args.output.string(), options.grid_name, r.active_voxels, h.x, h.y, h.z, r.index_lo[0], r.index_lo[1],
               r.index_lo[2], r.index_hi[0], r.index_hi[1], r.index_hi[2]);
    fmt::print("  values {:.4g} .. {:.4g} {}, filled volume {} (estimated {:.3g} voxels, {:.3g} MB)\n", r.min_value,
               r.max_value, options.unit, format_volume(r.filled_volume), r.estimate.voxels(),
               r.estimate.bytes / (1024.0 * 1024.0));
  }
  return 0;
}

void add_voxelize_subcommand(CLI::App& app, VoxelizeArgs& a) {
  CLI::App* c = app.add_subcommand("voxelize", "Turn a mesh or height field into a concentration grid (.vdb)");
  c->add_option("input", a.input, "Mesh (OBJ, PLY, glTF, ...) or height field (.pgm, .hf, .txt, .csv)")->required();
  c->add_option("-o,--output", a.output, "Output .vdb file")->required();
  c->add_option("--mode", a.mode, "solid (closed mesh, filled) | shell (open/thin mesh) | spill (footprint or height field)")
      ->capture_default_str();
  c->add_option("--voxel-size", a.voxel_size, "Metres per voxel: V, or vx,vy,vz for non-cubic voxels")->required();
  c->add_option("--thickness", a.thickness, "shell: full thickness in metres, centred on the surface")->check(Real(-kMaxFloatParam, kMaxFloatParam));
  c->add_option("--depth", a.depth, "spill: layer depth in metres (height field: multiplies the samples)")->check(Real(-kMaxFloatParam, kMaxFloatParam));
  c->add_option("--direction", a.direction, "spill: extrude along the footprint's normal or up (+y)")
      ->capture_default_str();
  c->add_option("--cell-size", a.cell_size, "height field: metres between samples (default: the voxel size in x)")->check(Real(-kMaxFloatParam, kMaxFloatParam));
  c->add_option("--concentration", a.concentration, "C in --unit (uniform value, noise mean, falloff peak; default 1)")->check(Real(-kMaxFloatParam, kMaxFloatParam));
  c->add_option("--unit", a.unit, "Unit of the stored values: M, mM, uM (µM) or nM")->capture_default_str();
  c->add_option("--profile", a.profile, "uniform | linear | noise | falloff | grid")->capture_default_str();
  c->add_option("--gradient", a.gradient, "linear: C0,C1 at the low and high end of the body along --axis");
  c->add_option("--axis", a.axis, "linear: x | y | z")->capture_default_str();
  c->add_option("--noise-seed", a.noise_seed, "noise: seed")->check(Unsigned64)->capture_default_str();
  c->add_option("--noise-scale", a.noise_scale, "noise: feature size in metres (0: a quarter of the body's size)")
      ->check(Real(0, kMaxFloatParam))
      ->capture_default_str();
  c->add_option("--noise-amplitude", a.noise_amplitude, "noise: relative modulation in [0, 1]")->check(Real(0, 1))->capture_default_str();
  c->add_option("--noise-octaves", a.noise_octaves, "noise: octaves, 1..8")->check(Integer(1, 8))->capture_default_str();
  c->add_option("--falloff-length", a.falloff_length, "falloff: length scale L in metres")->check(Real(-kMaxFloatParam, kMaxFloatParam));
  c->add_option("--falloff-shape", a.falloff_shape, "falloff: decay (C e^-d/L) | rise (C (1 - e^-d/L))")
      ->capture_default_str();
  c->add_option("--source-grid", a.source_grid, "grid: .vdb file to sample the concentration from");
  c->add_option("--source-grid-name", a.source_grid_name, "grid: name of the grid in --source-grid")
      ->capture_default_str();
  c->add_option("--grid-name", a.grid_name, "Name of the output grid")->capture_default_str();
  c->add_option("--scale", a.scale, "Input units to metres (0.001 for a mesh in mm)")->check(Real(-kMaxFloatParam, kMaxFloatParam))->capture_default_str();
  c->add_option("--translate", a.translate, "x,y,z in metres, applied after --scale");
  c->add_flag("-q,--quiet", a.quiet, "Print nothing");
}

}  // namespace chlorovdb::cli
