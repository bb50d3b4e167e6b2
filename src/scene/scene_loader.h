#pragma once
// Scene file (JSON, docs/scene-format.md) -> Scene. Every error names the
// file, the key path and the value.
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "scene/scene.h"

namespace chlorovdb {

// Command-line values that replace the file's `render` settings.
struct SceneOverrides {
  std::optional<int> width, height, spp, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> fluorescence, transmittance;
  std::optional<std::string> aovs;  // "alpha,depth,normal,albedo" (any of them; "" for none)
};

Scene load_scene(const std::filesystem::path& file, const SceneOverrides& overrides = {});

// The same from a parsed scene (e.g. edited in memory): `file` names the scene in
// errors, and relative paths (grids, meshes, spectra) resolve against its folder.
Scene load_scene(const nlohmann::json& json, const std::filesystem::path& file, const SceneOverrides& overrides = {});

// Loads `file` with each `sets` entry KEY=VALUE applied first (apply_scene_set),
// in memory: nothing is written beside the scene.
Scene load_scene(const std::filesystem::path& file, const SceneOverrides& overrides, std::span<const std::string> sets);

// Sets the value at KEY, a dotted path with array elements as name[i]
// ("media.solution.pigments[0].concentration"), creating objects along the way.
// `where` names the source of the edit in errors ("--set", "set=").
void set_scene_key(nlohmann::json& json, std::string_view key, nlohmann::json value, std::string_view where);

// KEY=VALUE, VALUE as JSON (a bare word that is not JSON is taken as a string):
// `--set render.skip_unneeded_work=false`. Throws InputError for a malformed edit.
void apply_scene_set(nlohmann::json& json, std::string_view key_equals_value);

}  // namespace chlorovdb
