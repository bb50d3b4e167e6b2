// `chlorovdb export-pbrt SCENE.json -o OUT.pbrt`: the scene in pbrt-v4's format
// for cross-checks (analysis/pbrt_export.h lists what maps how).
#include <fstream>

#include <fmt/format.h>

#include "analysis/pbrt_export.h"
#include "analysis/scene_variant.h"
#include "cli/commands.h"
#include "core/error.h"

namespace chlorovdb::cli {

namespace {

struct ExportPbrtArgs {
  std::filesystem::path scene;
  std::filesystem::path output;
  std::optional<int> spp;
  std::optional<std::string> resolution;
  bool ignore_fluorescence = false;
  int64_t max_grid_voxels = int64_t(256) * 256 * 256;
};

int export_pbrt_file(const ExportPbrtArgs& a) {
  SceneOverrides o;
  if (a.resolution) parse_resolution(*a.resolution, o);
  if (a.ignore_fluorescence) o.fluorescence = "off";
  const Scene scene = load_scene(a.scene, o);
  PbrtExportOptions po;
  po.ignore_fluorescence = a.ignore_fluorescence;
  po.spp = a.spp.value_or(0);
  po.max_grid_voxels = a.max_grid_voxels;
  std::filesystem::path out = a.output.empty() ? std::filesystem::path(a.scene.stem().string() + ".pbrt") : a.output;
  po.film_filename = out.stem().string() + ".exr";
  const PbrtExport e = export_pbrt(scene, a.scene, po);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::ofstream f(out);
  f << e.text;
  if (!f) throw InputError(out.string(), "", "", "cannot be written");
  for (const std::string& w : e.warnings) fmt::print(stderr, "warning: {}\n", w);
  fmt::print(stderr, "wrote {} (render with: pbrt {})\n", out.string(), out.string());
  return 0;
}

}  // namespace

Command add_export_pbrt_command(CLI::App& app) {
  auto args = std::make_shared<ExportPbrtArgs>();
  ExportPbrtArgs& r = *args;
  CLI::App* sub = app.add_subcommand("export-pbrt", "Write the scene in pbrt-v4's format (scenes without fluorescence)");
  sub->add_option("scene", r.scene, "Scene file")->required()->check(RegularFile);
  sub->add_option("-o,--output", r.output, "Output .pbrt (default: the scene's name in the current folder)");
  sub->add_option("--spp", r.spp, "pbrt pixel samples (default: the scene's spp)")->check(Integer(1, kMaxSpp));
  sub->add_option("--resolution", r.resolution, "Image size WxH");
  sub->add_flag("--ignore-fluorescence", r.ignore_fluorescence,
                "Export fluorescent pigments as absorbers (compare with render --fluorescence off)");
  sub->add_option("--max-grid-voxels", r.max_grid_voxels, "Refuse to dump grids with more voxels than this")
      ->check(Integer(1, INT64_MAX));
  return {sub, [args] { return export_pbrt_file(*args); }};
}

}  // namespace chlorovdb::cli
