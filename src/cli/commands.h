#pragma once
// One file per subcommand; each registers itself on the CLI11 app and returns
// the function main() calls when its subcommand was chosen.
#include <filesystem>
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "cli/options.h"

namespace chlorovdb::cli {

struct Command {
  CLI::App* subcommand;    // as registered on the app
  std::function<int()> run;  // called when that subcommand was given
};

// Like CLI::ExistingFile, but also refuses devices, FIFOs and sockets: a scene
// named /dev/zero or /dev/stdin would otherwise be read forever.
inline const CLI::Validator RegularFile(
    [](std::string& path) -> std::string {
      std::error_code ec;
      const auto status = std::filesystem::status(path, ec);
      if (ec || !std::filesystem::exists(status)) return "File does not exist: " + path;
      if (!std::filesystem::is_regular_file(status)) return "Not a regular file: " + path;
      return {};
    },
    "FILE");

Command add_render_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_voxelize_command(CLI::App& app);
Command add_converge_command(CLI::App& app);
Command add_reference_command(CLI::App& app);
Command add_export_pbrt_command(CLI::App& app);
Command add_merge_command(CLI::App& app);
Command add_measure_command(CLI::App& app);

}  // namespace chlorovdb::cli
