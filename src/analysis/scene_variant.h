#pragma once
// Loading a scene with command-line changes, for the tools that compare
// variants of one scene (converge, reference, the benchmark suite):
// SceneOverrides for the common settings, plus `--set KEY=VALUE` for any other
// key of the scene file (docs/scene-format.md), e.g.
//   --set render.skip_unneeded_work=false   --set media.solution.pigments[0].concentration=5
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "scene/scene.h"
#include "scene/scene_loader.h"

namespace chlorovdb {

// "WxH" -> overrides.width / height. Throws InputError naming `option`.
void parse_resolution(std::string_view text, SceneOverrides& overrides, std::string_view option = "--resolution");

// Loads `file` with `overrides`; each entry of `sets` is KEY=VALUE where KEY is a
// dotted path (array elements as name[i]) and VALUE is JSON (a bare word that
// is not JSON is taken as a string). With sets, the edited file is written
// beside the original (so relative paths still resolve) as a hidden temporary
// and removed after loading. Throws InputError for a malformed KEY=VALUE.
Scene load_scene_variant(const std::filesystem::path& file, const SceneOverrides& overrides,
                         std::span<const std::string> sets);

}  // namespace chlorovdb
