// chlorovdb command line: every subcommand registers itself (cli/commands.h);
// main only dispatches and turns errors into messages and exit codes.
#include <fmt/format.h>

#include "cli/commands.h"
#include "core/error.h"

using namespace chlorovdb;

int main(int argc, char** argv) {
  CLI::App app{"chlorovdb: spectral rendering of fluorescent pigments in OpenVDB volumes"};
  app.set_version_flag("--version", std::string("chlorovdb ") + CHLOROVDB_VERSION);
  app.require_subcommand(1);
  // One line per subcommand (cli/<name>_command.cpp).
  const std::vector<cli::Command> commands = {
      cli::add_render_command(app),
      cli::add_info_command(app),
      cli::add_voxelize_command(app),
      cli::add_converge_command(app),
      cli::add_reference_command(app),
      cli::add_export_pbrt_command(app),
      cli::add_merge_command(app),
      cli::add_measure_command(app),
  };
  CLI11_PARSE(app, argc, argv);
  try {
    for (const cli::Command& c : commands)
      if (c.subcommand->parsed()) return c.run();
  } catch (const InputError& e) {
    fmt::print(stderr, "chlorovdb: error: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "chlorovdb: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
