#include "scene/param_reader.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include <fmt/format.h>

#include "core/error.h"
#include "core/number.h"

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

namespace {

// Line and column of byte offset `byte` (1-based, as nlohmann reports it).
std::string position(std::string_view text, size_t byte) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') ++line, col = 1;
    else ++col;
  }
  return fmt::format("{}:{}", line, col);
}

// A SAX pass before the document is built: refuses a key given twice in one
// object (nlohmann would keep the last one silently) and nesting deeper than
// kMaxJsonDepth (the DOM and every recursive walk over it would exhaust the
// stack first). Records the key path of the offence for the message.
class StructureCheck : public nlohmann::json_sax<nlohmann::json> {
 public:
  std::string problem, path, value;
  std::optional<size_t> syntax_error_byte;
  std::string syntax_error;

  bool null() override { return scalar(); }
  bool boolean(bool) override { return scalar(); }
  bool number_integer(number_integer_t) override { return scalar(); }
  bool number_unsigned(number_unsigned_t) override { return scalar(); }
  bool number_float(number_float_t, const string_t&) override { return scalar(); }
  bool string(string_t&) override { return scalar(); }
  bool binary(binary_t&) override { return scalar(); }
  bool start_object(std::size_t) override { return open(true); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    Level& l = levels_.back();
    l.name = k;
    if (!l.keys.insert(k).second) {
      problem = "duplicate key: each key may appear once in an object (the earlier value would be silently ignored)";
      path = current_path();
      return false;
    }
    return true;
  }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) override {
    syntax_error_byte = position;  // e may be a parse_error or an out_of_range (a number beyond double: 1e400)
    syntax_error = e.what();
    return false;
  }

 private:
  struct Level {
    bool object;
    std::set<std::string> keys;
    std::string name;  // current key (objects)
    size_t index = 0;  // current element (arrays)
  };
  std::vector<Level> levels_;

  std::string current_path() const {
    std::string p;
    for (const Level& l : levels_) {
      if (l.object) p += (p.empty() ? "" : ".") + l.name;
      else p += fmt::format("[{}]", l.index);
    }
    return p.empty() ? "(top level)" : p;
  }
  void element_done() {
    if (!levels_.empty() && !levels_.back().object) ++levels_.back().index;
  }
  bool scalar() {
    element_done();
    return true;
  }
  bool open(bool object) {
    if (levels_.size() >= ParamReader::kMaxJsonDepth) {
      problem = fmt::format("nested deeper than {} levels", ParamReader::kMaxJsonDepth);
      path = current_path();
      return false;
    }
    levels_.push_back({object, {}, {}, 0});
    return true;
  }
  bool close() {
    levels_.pop_back();
    element_done();
    return true;
  }
};

}  // namespace

nlohmann::json ParamReader::parse_text(const std::string& text, const std::string& origin) {
  StructureCheck check;
  try {
    const bool ok = nlohmann::json::sax_parse(text, &check, nlohmann::json::input_format_t::json, /*strict=*/true,
                                              /*ignore_comments=*/true);
    if (!ok && check.syntax_error_byte)
      throw InputError(fmt::format("{}:{}", origin, position(text, *check.syntax_error_byte)), "", "",
                       fmt::format("malformed JSON ({})", check.syntax_error));
    if (!ok) throw InputError(origin, check.path, "", check.problem);
    return nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(fmt::format("{}:{}", origin, position(text, e.byte)), "", "", fmt::format("malformed JSON ({})", e.what()));
  } catch (const nlohmann::json::exception& e) {
    // e.g. out_of_range.406: a number beyond double range such as 1e400.
    throw InputError(origin, "", "", fmt::format("unreadable JSON ({})", e.what()));
  }
}

nlohmann::json ParamReader::parse_file(const std::filesystem::path& file) {
  // A device or pipe (/dev/zero) would be read forever: only regular files are scenes.
  std::error_code ec;
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec))
    throw InputError(file.string(), "", "", "not a regular file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "", "cannot open the scene file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_text(text, file.string());
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
  if (const auto problem = range_problem(d, std::max<double>(lo, -kMaxFloatParam), std::min<double>(hi, kMaxFloatParam)))
    fail(key, *problem);
  return float(d);
}

float ParamReader::get_float(const std::string& key, float fallback, float lo, float hi) {
  return has(key) ? require_float(key, lo, hi) : fallback;
}

namespace {

// A JSON integer as int64, or nullopt when it does not fit (unsigned beyond
// INT64_MAX would wrap through get<long long>).
std::optional<int64_t> json_int64(const nlohmann::json& v) {
  if (v.is_number_unsigned()) {
    const uint64_t u = v.get<uint64_t>();
    if (u > uint64_t(INT64_MAX)) return std::nullopt;
    return int64_t(u);
  }
  return v.get<int64_t>();
}

}  // namespace

int ParamReader::get_int(const std::string& key, int fallback, int lo, int hi) {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_number_integer()) fail(key, "expected an integer");
  const std::optional<int64_t> i = json_int64(v);
  if (!i || range_problem(double(*i), lo, hi)) fail(key, fmt::format("must be an integer in [{}, {}]", lo, hi));
  return int(*i);
}

uint64_t ParamReader::get_uint64(const std::string& key, uint64_t fallback) {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<int64_t>() < 0))
    fail(key, fmt::format("expected an integer in [0, {}]", UINT64_MAX));
  return v.get<uint64_t>();
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
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number()) fail(key, fmt::format("element {} is not a number", i));
    const double d = v[i].get<double>();
    if (const auto problem = range_problem(d, -kMaxFloatParam, kMaxFloatParam))
      fail(key, fmt::format("element {} = {}: {}", i, show(v[i]), *problem));
    out.push_back(float(d));
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
