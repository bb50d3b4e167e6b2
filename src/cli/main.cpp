// chlorovdb command line: parses arguments and hands them to cli/commands.h.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli/commands.h"
#include "core/error.h"

using namespace chlorovdb;

int main(int argc, char** argv) {
  CLI::App app{"chlorovdb: spectral rendering of fluorescent pigments in OpenVDB volumes"};
  app.set_version_flag("--version", std::string("chlorovdb ") + CHLOROVDB_VERSION);
  app.require_subcommand(1);

  cli::RenderArgs r;
  CLI::App* render = app.add_subcommand("render", "Render a scene to a linear EXR and a PNG preview");
  render->add_option("scene", r.scene, "Scene file (JSON, docs/scene-format.md)")->required()->check(CLI::ExistingFile);
  render->add_option("-o,--output", r.output, "Output EXR (default: the scene's name in the current folder)");
  render->add_option("--spp", r.spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24));
  render->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  render->add_option("--seed", r.seed, "Seed of the per-pixel random streams");
  render->add_option("--resolution", r.resolution, "Image size WxH, e.g. 640x480");
  render->add_option("--wavelengths", r.wavelengths, "Wavelengths per camera path")->check(CLI::Range(1, 16));
  render->add_option("--exposure", r.exposure, "PNG preview exposure in stops");
  render->add_option("--fluorescence", r.fluorescence, "auto | direct | full | reference | off");
  render->add_option("--transmittance", r.transmittance, "auto | ratio | residual_ratio | delta");
  render->add_flag("-q,--quiet", r.quiet, "No progress bar");

  std::filesystem::path vdb;
  CLI::App* info = app.add_subcommand("info", "List the grids of a .vdb file and check their values");
  info->add_option("file", vdb, ".vdb file")->required();

  CLI11_PARSE(app, argc, argv);
  try {
    if (*render) return cli::render(r);
    if (*info) return cli::info(vdb);
  } catch (const InputError& e) {
    fmt::print(stderr, "chlorovdb: error: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "chlorovdb: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
