#pragma once
// Partial renders: a pixel window (crop) of the full image and a set of sample
// ranges of every pixel in it. Independent processes render disjoint parts;
// merge.h combines them into the image one run would give (docs/distributed.md).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/image.h"

namespace chlorovdb {

// Pixels [x0, x1) x [y0, y1) of the full image.
struct PixelWindow {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool intersects(const PixelWindow& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool operator==(const PixelWindow&) const = default;
};

// Samples [begin, end) of every pixel (sample indices select the random streams).
struct SampleRange {
  int begin = 0, end = 0;
  int size() const { return end - begin; }
  bool intersects(const SampleRange& o) const { return begin < o.end && o.begin < end; }
  bool operator==(const SampleRange&) const = default;
};

// "x0,y0,x1,y1" with 0 <= x0 < x1 <= width, 0 <= y0 < y1 <= height; InputError naming `option` otherwise.
PixelWindow parse_crop(std::string_view text, int width, int height, std::string_view option = "--crop");
// "A:B" with 0 <= A < B <= 2^30.
SampleRange parse_sample_range(std::string_view text, std::string_view option = "--sample-range");
std::string to_string(const PixelWindow& w);                 // "x0,y0,x1,y1"
std::string to_string(const std::vector<SampleRange>& ranges);  // "A:B,C:D"
// Sorted, adjacent ranges joined; empty ranges dropped.
std::vector<SampleRange> normalized(std::vector<SampleRange> ranges);

// Settings that must agree between the parts of one image, and between a
// checkpoint and the render resuming it: (key, value) pairs such as
// ("scene_hash", "3f2a…"), ("seed", "7"), ("wavelengths", "8").
using Signature = std::vector<std::pair<std::string, std::string>>;
struct SignatureMismatch {
  std::string key, a, b;  // a value is "(missing)" when only the other signature has the key
};
// The first key whose values differ, if any.
std::optional<SignatureMismatch> signature_difference(const Signature& a, const Signature& b);

// What one partial render covers.
struct PartInfo {
  int full_width = 0, full_height = 0;
  PixelWindow crop;                 // the part's pixels; its image/film has the crop's size
  std::vector<SampleRange> ranges;  // samples rendered, disjoint
  Signature signature;
  int samples() const;              // samples per pixel of the part
};

// Metadata keys of a part in an EXR ("chlorovdb:" attributes): full_resolution
// "WxH", crop "x0,y0,x1,y1", sample_ranges "A:B[,C:D…]", signature "key=value"
// lines. read_part_metadata throws InputError naming `file` when one is missing.
void set_part_metadata(Metadata& metadata, const PartInfo& part);
PartInfo read_part_metadata(const Metadata& metadata, const std::filesystem::path& file);

// 64-bit FNV-1a of a file's bytes as 16 hex digits (the scene hash of a signature).
std::string hash_file(const std::filesystem::path& file);
// The same of a string (a scene held in memory, or a file's hash plus its edits).
std::string hash_text(std::string_view text);

}  // namespace chlorovdb
