#include "analysis/scene_variant.h"

#include <cstdio>

#include <fmt/format.h>

#include "core/error.h"
#include "core/number.h"

namespace chlorovdb {

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

}  // namespace chlorovdb
