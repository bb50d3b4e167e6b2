#include "analysis/scene_variant.h"

#include <cstdio>
#include <fstream>
#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/number.h"
#include "scene/param_reader.h"

namespace chlorovdb {

namespace {

// Applies KEY=VALUE to `json`, creating objects along the way.
void apply_set(nlohmann::json& json, const std::string& set) {
  const size_t eq = set.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("command line", "--set", set, "expected KEY=VALUE, e.g. render.skip_unneeded_work=false");
  const std::string key = set.substr(0, eq), text = set.substr(eq + 1);
  // An array or object must be valid JSON (checked like a scene file: no
  // duplicate keys, bounded nesting); any other word that is not JSON is a string.
  nlohmann::json value;
  if (!text.empty() && (text[0] == '[' || text[0] == '{')) value = ParamReader::parse_text(text, "command line: --set " + key);
  else if (value = nlohmann::json::parse(text, nullptr, false); value.is_discarded()) value = text;
  nlohmann::json* node = &json;
  size_t start = 0;
  while (start <= key.size()) {
    size_t end = key.find('.', start);
    if (end == std::string::npos) end = key.size();
    std::string part = key.substr(start, end - start);
    std::optional<size_t> index;
    if (const size_t open = part.find('['); open != std::string::npos) {
      if (part.back() != ']') throw InputError("command line", "--set", set, "malformed index in \"" + part + "\"");
      index = std::stoul(part.substr(open + 1, part.size() - open - 2));
      part = part.substr(0, open);
    }
    if (part.empty()) throw InputError("command line", "--set", set, "empty key component");
    if (!node->is_object()) throw InputError("command line", "--set", set, "\"" + part + "\" is not inside an object");
    node = &(*node)[part];
    if (index) {
      if (!node->is_array() || *index >= node->size())
        throw InputError("command line", "--set", set, fmt::format("\"{}\" has no element {}", part, *index));
      node = &(*node)[*index];
    }
    start = end + 1;
  }
  *node = value;
}

}  // namespace

void parse_resolution(std::string_view text, SceneOverrides& o, std::string_view option) {
  // Each side parsed whole and in int64, so "4294967312x12" cannot wrap to 16.
  const size_t x = text.find_first_of("xX");
  const std::optional<int64_t> w = x == std::string_view::npos ? std::nullopt : parse_int64(text.substr(0, x));
  const std::optional<int64_t> h = x == std::string_view::npos ? std::nullopt : parse_int64(text.substr(x + 1));
  if (!w || !h || *w < 1 || *h < 1 || *w > kMaxImageSide || *h > kMaxImageSide)
    throw InputError("command line", option, text,
                     fmt::format("expected WxH with 1 <= W, H <= {}, e.g. 640x480", kMaxImageSide));
  o.width = int(*w);
  o.height = int(*h);
}

Scene load_scene_variant(const std::filesystem::path& file, const SceneOverrides& overrides,
                         std::span<const std::string> sets) {
  if (sets.empty()) return load_scene(file, overrides);
  nlohmann::json json = ParamReader::parse_file(file);
  for (const std::string& s : sets) apply_set(json, s);
  const std::filesystem::path tmp =
      file.parent_path() / fmt::format(".{}.variant-{}.json", file.stem().string(), ::getpid());
  {
    std::ofstream f(tmp);
    f << json.dump(2);
    if (!f) throw InputError(tmp.string(), "", "", "cannot write the edited scene beside the original");
  }
  struct Remove {
    std::filesystem::path p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
  } remove{tmp};
  try {
    return load_scene(tmp, overrides);
  } catch (const InputError& e) {
    // Name the user's file, not the temporary, and say it was edited.
    std::string message = e.what();
    const std::string from = tmp.string(), to = file.string() + " (with --set)";
    for (size_t at; (at = message.find(from)) != std::string::npos;) message.replace(at, from.size(), to);
    throw InputError(message);
  }
}

}  // namespace chlorovdb
