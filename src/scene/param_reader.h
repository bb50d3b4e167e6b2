#pragma once
// Validating view on one JSON object of a scene file. Every getter records the
// key as used; finish() rejects the keys nobody asked for, naming the nearest
// valid one ("did you mean"). All errors carry file, key path and value.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/vec.h"

namespace chlorovdb {

class ParamReader {
 public:
  ParamReader(const nlohmann::json& object, std::filesystem::path file, std::string key_path);

  // Deepest nesting a scene may use (scenes need about 6 levels).
  static constexpr size_t kMaxJsonDepth = 64;
  // Parse a whole file; malformed JSON is an InputError with line and column,
  // and so is a key repeated within one object or nesting beyond kMaxJsonDepth.
  static nlohmann::json parse_file(const std::filesystem::path& file);
  // The same for JSON text from elsewhere; `origin` names it in errors.
  static nlohmann::json parse_text(const std::string& text, const std::string& origin);

  bool has(const std::string& key) const;

  float get_float(const std::string& key, float fallback, float lo = -3e38f, float hi = 3e38f);
  float require_float(const std::string& key, float lo = -3e38f, float hi = 3e38f);
  int get_int(const std::string& key, int fallback, int lo = INT32_MIN, int hi = INT32_MAX);
  // A non-negative integer up to 2^64 - 1 (seeds).
  uint64_t get_uint64(const std::string& key, uint64_t fallback);
  bool get_bool(const std::string& key, bool fallback);
  std::string get_string(const std::string& key, const std::string& fallback);
  std::string require_string(const std::string& key);
  // One of `choices`, else an error listing them and the nearest.
  std::string get_enum(const std::string& key, const std::string& fallback, const std::vector<std::string>& choices);
  Vec3 get_vec3(const std::string& key, const Vec3& fallback);
  Vec3 require_vec3(const std::string& key);
  std::vector<float> get_floats(const std::string& key, const std::vector<float>& fallback, size_t min_count = 0);
  // A path relative to the scene file's folder (absolute paths are kept).
  std::filesystem::path require_path(const std::string& key);

  ParamReader child(const std::string& key);                  // required object
  std::optional<ParamReader> optional_child(const std::string& key);
  std::vector<ParamReader> children_array(const std::string& key);  // array of objects (may be absent)
  std::vector<std::pair<std::string, ParamReader>> children_map(const std::string& key);  // object of objects
  const nlohmann::json& raw(const std::string& key);  // marks the key used

  // Throws InputError for any key never read.
  void finish() const;
  // Throws InputError about `key` (or this object when key is empty) with `problem`.
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

  const std::filesystem::path& file() const { return file_; }
  std::string key_path(const std::string& key) const;

 private:
  const nlohmann::json& value(const std::string& key);
  const nlohmann::json* object_;
  std::filesystem::path file_;
  std::string path_;
  // Every key a getter asked for, present or not: the valid vocabulary of this object.
  mutable std::vector<std::string> known_;
};

}  // namespace chlorovdb
