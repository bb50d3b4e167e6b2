#pragma once
// Scene file (JSON, docs/scene-format.md) -> Scene. Every error names the
// file, the key path and the value.
#include <filesystem>
#include <optional>
#include <string>

#include "scene/scene.h"

namespace chlorovdb {

// Command-line values that replace the file's `render` settings.
struct SceneOverrides {
  std::optional<int> width, height, spp, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> fluorescence, transmittance;
};

Scene load_scene(const std::filesystem::path& file, const SceneOverrides& overrides = {});

}  // namespace chlorovdb
