#include "analysis/scene_variant.h"

#include <cstdio>

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {

void parse_resolution(std::string_view text, SceneOverrides& o, std::string_view option) {
  const std::string s(text);
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 65536 || h > 65536)
    throw InputError("command line", option, s, "expected WxH with 1 <= W, H <= 65536, e.g. 640x480");
  o.width = w;
  o.height = h;
}

}  // namespace chlorovdb
