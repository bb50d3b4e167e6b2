#pragma once
// Enum keywords in scene files, the CLI and the Python module: each enum has a
// to_string(E) giving its keyword, and parse_keyword reads one back.
#include <initializer_list>
#include <string_view>

namespace chlorovdb {

// Sets *out to the value among `values` whose to_string (found by argument-
// dependent lookup) is `word`; false, *out untouched, if none is.
template <typename Enum>
bool parse_keyword(std::string_view word, std::initializer_list<Enum> values, Enum* out) {
  for (Enum v : values)
    if (word == to_string(v)) {
      *out = v;
      return true;
    }
  return false;
}

}  // namespace chlorovdb
