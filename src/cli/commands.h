#pragma once
// One file per subcommand; each registers itself on the CLI11 app and returns
// the function main() calls when its subcommand was chosen.
#include <functional>

#include <CLI/CLI.hpp>

namespace chlorovdb::cli {

struct Command {
  CLI::App* subcommand;    // as registered on the app
  std::function<int()> run;  // called when that subcommand was given
};

Command add_render_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_voxelize_command(CLI::App& app);
Command add_converge_command(CLI::App& app);
Command add_reference_command(CLI::App& app);
Command add_export_pbrt_command(CLI::App& app);
Command add_merge_command(CLI::App& app);

}  // namespace chlorovdb::cli
