#pragma once
// `chlorovdb merge`: partial renders (disjoint crops and/or sample ranges of one
// scene, seed and settings) combined into the image one run would give.
#include <filesystem>
#include <vector>

#include "checkpoint/partition.h"
#include "io/image.h"

namespace chlorovdb {

struct MergeSummary {
  int parts = 0;
  int samples_per_pixel = 0;
  std::vector<SampleRange> ranges;  // every pixel's samples
  bool exact = false;               // from checkpoints (double sums), not EXR means
};

// Every file is either an EXR written by `chlorovdb render` (float means, weighted
// by their sample counts: equal to one run within float rounding) or a checkpoint
// (raw double sums: equal to one run within double rounding); mixing is refused.
// The parts must agree on resolution, layers and signature, must not render the
// same sample of the same pixel twice, and together must give every pixel the
// same samples; otherwise InputError names the files and the pixel or sample at fault.
// Parts are combined in a fixed order (by first sample, then crop), whatever the
// order of `files`. The image has the full resolution and every layer.
Image merge_parts(const std::vector<std::filesystem::path>& files, MergeSummary* summary = nullptr);

}  // namespace chlorovdb
