#include "checkpoint/partition.h"

#include <algorithm>
#include <charconv>
#include <fstream>

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {

namespace {

constexpr int kMaxSample = 1 << 30;

// Integers separated by `sep`; false unless there are exactly `count` of them and nothing else.
bool parse_ints(std::string_view text, char sep, int count, int* out) {
  for (int i = 0; i < count; ++i) {
    const char* end = text.data() + text.size();
    const auto [p, ec] = std::from_chars(text.data(), end, out[i]);
    if (ec != std::errc() || p == text.data()) return false;
    text.remove_prefix(size_t(p - text.data()));
    if (i + 1 < count) {
      if (text.empty() || text.front() != sep) return false;
      text.remove_prefix(1);
    }
  }
  return text.empty();
}

std::string value_text(const MetadataValue& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* i = std::get_if<int>(&v)) return std::to_string(*i);
  return fmt::format("{}", std::get<double>(v));
}

}  // namespace

PixelWindow parse_crop(std::string_view text, int width, int height, std::string_view option) {
  int v[4];
  if (!parse_ints(text, ',', 4, v))
    throw InputError("command line", option, text, "expected x0,y0,x1,y1 (pixels [x0, x1) x [y0, y1)), e.g. 0,0,160,120");
  const PixelWindow w{v[0], v[1], v[2], v[3]};
  if (w.x0 < 0 || w.y0 < 0 || w.x1 > width || w.y1 > height || w.empty())
    throw InputError("command line", option, text,
                     fmt::format("needs 0 <= x0 < x1 <= {} and 0 <= y0 < y1 <= {} (the image is {}x{})", width, height,
                                 width, height));
  return w;
}

SampleRange parse_sample_range(std::string_view text, std::string_view option) {
  int v[2];
  if (!parse_ints(text, ':', 2, v))
    throw InputError("command line", option, text, "expected A:B (samples [A, B) of every pixel), e.g. 0:64");
  if (v[0] < 0 || v[1] <= v[0] || v[1] > kMaxSample)
    throw InputError("command line", option, text, fmt::format("needs 0 <= A < B <= {}", kMaxSample));
  return {v[0], v[1]};
}

std::string to_string(const PixelWindow& w) { return fmt::format("{},{},{},{}", w.x0, w.y0, w.x1, w.y1); }

std::string to_string(const std::vector<SampleRange>& ranges) {
  std::string s;
  for (const SampleRange& r : ranges) s += fmt::format("{}{}:{}", s.empty() ? "" : ",", r.begin, r.end);
  return s;
}

std::vector<SampleRange> normalized(std::vector<SampleRange> ranges) {
  std::erase_if(ranges, [](const SampleRange& r) { return r.size() <= 0; });
  std::sort(ranges.begin(), ranges.end(), [](const SampleRange& a, const SampleRange& b) { return a.begin < b.begin; });
  std::vector<SampleRange> out;
  for (const SampleRange& r : ranges) {
    if (!out.empty() && r.begin <= out.back().end) out.back().end = std::max(out.back().end, r.end);
    else out.push_back(r);
  }
  return out;
}

std::optional<SignatureMismatch> signature_difference(const Signature& a, const Signature& b) {
  for (const auto& [key, value] : a) {
    // Init-captures: clang before 16 cannot capture a structured binding (C++20 allows it).
    const auto it = std::find_if(b.begin(), b.end(), [&k = key](const auto& e) { return e.first == k; });
    if (it == b.end()) return SignatureMismatch{key, value, "(missing)"};
    if (it->second != value) return SignatureMismatch{key, value, it->second};
  }
  for (const auto& [key, value] : b)
    if (std::none_of(a.begin(), a.end(), [&k = key](const auto& e) { return e.first == k; }))
      return SignatureMismatch{key, "(missing)", value};
  return std::nullopt;
}

int PartInfo::samples() const {
  int n = 0;
  for (const SampleRange& r : ranges) n += r.size();
  return n;
}

void set_part_metadata(Metadata& metadata, const PartInfo& part) {
  metadata.set("full_resolution", fmt::format("{}x{}", part.full_width, part.full_height));
  metadata.set("crop", to_string(part.crop));
  metadata.set("sample_ranges", to_string(part.ranges));
  std::string sig;
  for (const auto& [key, value] : part.signature) sig += fmt::format("{}{}={}", sig.empty() ? "" : "\n", key, value);
  metadata.set("signature", sig);
}

PartInfo read_part_metadata(const Metadata& metadata, const std::filesystem::path& file) {
  auto get = [&](std::string_view key) {
    const MetadataValue* v = metadata.find(key);
    if (!v)
      throw InputError(file.string(), fmt::format("chlorovdb:{}", key), "(missing)",
                       "not a part written by `chlorovdb render` (EXR metadata lacks the partition keys)");
    return value_text(*v);
  };
  PartInfo part;
  const std::string res = get("full_resolution");
  int wh[2];
  if (!parse_ints(res, 'x', 2, wh) || wh[0] < 1 || wh[1] < 1)
    throw InputError(file.string(), "chlorovdb:full_resolution", res, "expected WxH");
  part.full_width = wh[0];
  part.full_height = wh[1];
  const std::string crop = get("crop");
  try {
    part.crop = parse_crop(crop, part.full_width, part.full_height, "chlorovdb:crop");
  } catch (const InputError& e) {
    throw InputError(file.string(), "chlorovdb:crop", crop, "not a window inside full_resolution");
  }
  const std::string ranges = get("sample_ranges");
  for (size_t start = 0; start <= ranges.size();) {
    const size_t comma = std::min(ranges.find(',', start), ranges.size());
    try {
      part.ranges.push_back(parse_sample_range(std::string_view(ranges).substr(start, comma - start), "chlorovdb:sample_ranges"));
    } catch (const InputError&) {
      throw InputError(file.string(), "chlorovdb:sample_ranges", ranges, "expected A:B[,C:D...]");
    }
    start = comma + 1;
  }
  const std::string sig = get("signature");
  for (size_t start = 0; start < sig.size();) {
    const size_t nl = std::min(sig.find('\n', start), sig.size());
    const std::string line = sig.substr(start, nl - start);
    const size_t eq = line.find('=');
    if (eq == std::string::npos) throw InputError(file.string(), "chlorovdb:signature", line, "expected key=value lines");
    part.signature.emplace_back(line.substr(0, eq), line.substr(eq + 1));
    start = nl + 1;
  }
  return part;
}

namespace {
constexpr uint64_t kFnvBasis = 0xcbf29ce484222325ULL;
uint64_t fnv1a(uint64_t h, const char* bytes, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ uint8_t(bytes[i])) * 0x100000001b3ULL;
  return h;
}
}  // namespace

std::string hash_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "", "cannot read the file to hash it");
  uint64_t h = kFnvBasis;
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    h = fnv1a(h, buf, size_t(in.gcount()));
  }
  return fmt::format("{:016x}", h);
}

std::string hash_text(std::string_view text) { return fmt::format("{:016x}", fnv1a(kFnvBasis, text.data(), text.size())); }

}  // namespace chlorovdb
