#pragma once
// One function per subcommand; main.cpp only wires them to CLI11.
#include <filesystem>
#include <optional>
#include <string>

namespace chlorovdb::cli {

struct RenderArgs {
  std::filesystem::path scene;
  std::filesystem::path output;  // .exr; the PNG preview goes beside it
  std::optional<int> spp, threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution;  // "WxH"
  std::optional<float> exposure;
  std::optional<std::string> fluorescence, transmittance;
  bool quiet = false;
};

int render(const RenderArgs& args);
int info(const std::filesystem::path& vdb_file);

}  // namespace chlorovdb::cli
