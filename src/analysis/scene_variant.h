#pragma once
// Command-line text -> SceneOverrides. Edits of any other scene key
// (`--set KEY=VALUE`) are load_scene's (scene/scene_loader.h).
#include <filesystem>
#include <string>
#include <string_view>

#include "scene/scene.h"
#include "scene/scene_loader.h"

namespace chlorovdb {

// "WxH" -> overrides.width / height. Throws InputError naming `option`.
void parse_resolution(std::string_view text, SceneOverrides& overrides, std::string_view option = "--resolution");

}  // namespace chlorovdb
