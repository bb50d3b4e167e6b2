#include "scene/param_reader.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {

namespace {

std::string show(const nlohmann::json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

}  // namespace

ParamReader::ParamReader(const nlohmann::json& object, std::filesystem::path file, std::string key_path)
    : object_(&object), file_(std::move(file)), path_(std::move(key_path)) {
  if (!object.is_object()) fail("", fmt::format("expected an object, got {}", show(object)));
}

nlohmann::json ParamReader::parse_file(const std::filesystem::path& file) {
  // A device or pipe (/dev/zero) would be read forever: only regular files are scenes.
  std::error_code ec;
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec))
    throw InputError(file.string(), "", "", "not a regular file");
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "", "cannot open the scene file");
  try {
    return nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the offset; report line and column for humans.
    in.clear();
    in.seekg(0);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    size_t line = 1, col = 1;
    for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') ++line, col = 1;
      else ++col;
    }
    throw InputError(fmt::format("{}:{}:{}", file.string(), line, col), "", "",
                     fmt::format("malformed JSON ({})", e.what()));
  } catch (const nlohmann::json::exception& e) {
    // e.g. out_of_range.406: a number beyond double range such as 1e400.
    throw InputError(file.string(), "", "", fmt::format("unreadable JSON ({})", e.what()));
  }
}

std::string ParamReader::key_path(const std::string& key) const {
  if (key.empty()) return path_.empty() ? "(top level)" : path_;
  return path_.empty() ? key : path_ + "." + key;
}

void ParamReader::fail(const std::string& key, const std::string& problem) const {
  std::string val;
  if (!key.empty() && object_->contains(key)) val = show((*object_)[key]);
  throw InputError(file_.string(), key_path(key), val, problem);
}

bool ParamReader::has(const std::string& key) const {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
  return object_->contains(key);
}

const nlohmann::json& ParamReader::value(const std::string& key) {
  has(key);
  return (*object_)[key];
}

const nlohmann::json& ParamReader::raw(const std::string& key) {
  if (!has(key)) fail(key, "missing required key");
  return value(key);
}

float ParamReader::require_float(const std::string& key, float lo, float hi) {
  const auto& v = raw(key);
  if (!v.is_number()) fail(key, "expected a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(key, "must be finite");
  if (d < lo || d > hi) {
    if (hi >= 3e38f) fail(key, fmt::format("must be >= {}", lo));
    if (lo <= -3e38f) fail(key, fmt::format("must be <= {}", hi));
    fail(key, fmt::format("must be in [{}, {}]", lo, hi));
  }
  return float(d);
}

float ParamReader::get_float(const std::string& key, float fallback, float lo, float hi) {
  return has(key) ? require_float(key, lo, hi) : fallback;
}

int ParamReader::get_int(const std::string& key, int fallback, int lo, int hi) {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_number_integer()) fail(key, "expected an integer");
  const long long i = v.get<long long>();
  if (i < lo || i > hi) fail(key, fmt::format("must be in [{}, {}]", lo, hi));
  return int(i);
}

bool ParamReader::get_bool(const std::string& key, bool fallback) {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_boolean()) fail(key, "expected true or false");
  return v.get<bool>();
}

std::string ParamReader::require_string(const std::string& key) {
  const auto& v = raw(key);
  if (!v.is_string()) fail(key, "expected a string");
  return v.get<std::string>();
}

std::string ParamReader::get_string(const std::string& key, const std::string& fallback) {
  return has(key) ? require_string(key) : fallback;
}

std::string ParamReader::get_enum(const std::string& key, const std::string& fallback,
                                  const std::vector<std::string>& choices) {
  const std::string s = get_string(key, fallback);
  if (std::find(choices.begin(), choices.end(), s) != choices.end()) return s;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  const std::string near = nearest_word(s, choices);
  fail(key, fmt::format("must be one of: {}{}", list, near.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", near)));
}

std::vector<float> ParamReader::get_floats(const std::string& key, const std::vector<float>& fallback,
                                           size_t min_count) {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_array()) fail(key, "expected an array of numbers");
  std::vector<float> out;
  for (const auto& e : v) {
    if (!e.is_number() || !std::isfinite(e.get<double>())) fail(key, "every element must be a finite number");
    out.push_back(e.get<float>());
  }
  if (out.size() < min_count) fail(key, fmt::format("needs at least {} numbers", min_count));
  return out;
}

Vec3 ParamReader::require_vec3(const std::string& key) {
  raw(key);
  const auto f = get_floats(key, {});
  if (f.size() != 3) fail(key, "expected [x, y, z]");
  return {f[0], f[1], f[2]};
}

Vec3 ParamReader::get_vec3(const std::string& key, const Vec3& fallback) {
  return has(key) ? require_vec3(key) : fallback;
}

std::filesystem::path ParamReader::require_path(const std::string& key) {
  const std::filesystem::path p = require_string(key);
  return p.is_absolute() ? p : file_.parent_path() / p;
}

ParamReader ParamReader::child(const std::string& key) {
  const auto& v = raw(key);
  if (!v.is_object()) fail(key, "expected an object { ... }");
  return ParamReader(v, file_, key_path(key));
}

std::optional<ParamReader> ParamReader::optional_child(const std::string& key) {
  if (!has(key)) return std::nullopt;
  return child(key);
}

std::vector<ParamReader> ParamReader::children_array(const std::string& key) {
  std::vector<ParamReader> out;
  if (!has(key)) return out;
  const auto& v = value(key);
  if (!v.is_array()) fail(key, "expected an array [ {...}, ... ]");
  for (size_t i = 0; i < v.size(); ++i) out.emplace_back(v[i], file_, fmt::format("{}[{}]", key_path(key), i));
  return out;
}

std::vector<std::pair<std::string, ParamReader>> ParamReader::children_map(const std::string& key) {
  std::vector<std::pair<std::string, ParamReader>> out;
  if (!has(key)) return out;
  const auto& v = value(key);
  if (!v.is_object()) fail(key, "expected an object of named entries { \"name\": {...} }");
  for (const auto& [name, e] : v.items()) out.emplace_back(name, ParamReader(e, file_, key_path(key) + "." + name));
  return out;
}

void ParamReader::finish() const {
  for (const auto& [k, v] : object_->items()) {
    if (std::find(known_.begin(), known_.end(), k) != known_.end()) continue;
    const std::string near = nearest_word(k, known_);
    throw InputError(file_.string(), key_path(k), "",
                     near.empty() ? "unknown key" : fmt::format("unknown key (did you mean \"{}\"?)", near));
  }
}

}  // namespace chlorovdb
