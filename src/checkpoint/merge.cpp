#include "checkpoint/merge.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "checkpoint/checkpoint.h"
#include "core/error.h"
#include "core/rng.h"
#include "film/film.h"

namespace chlorovdb {

namespace {

// The depth AOV (film/film.h): Z, a mean over the samples that hit a surface, and their fraction.
bool is_depth_layer(const ImageLayer& l) { return l.name == "depth" && l.channels == std::vector<std::string>{"Z", "coverage"}; }

struct Part {
  std::filesystem::path file;
  PartInfo info;
};

std::string describe(const std::vector<SampleRange>& ranges) {
  const std::string s = to_string(normalized(ranges));
  return s.empty() ? "no samples" : "samples " + s;
}

// Orders parts canonically (so the sums do not depend on the command line's
// order) and checks they tile the image x samples space exactly once. Returns
// every pixel's samples.
std::vector<SampleRange> check_parts(std::vector<Part>& parts) {
  if (parts.empty()) throw InputError("command line", "PART", "", "nothing to merge");
  std::stable_sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) {
    const int sa = a.info.ranges.empty() ? 0 : a.info.ranges.front().begin, sb = b.info.ranges.empty() ? 0 : b.info.ranges.front().begin;
    return std::tie(sa, a.info.crop.y0, a.info.crop.x0) < std::tie(sb, b.info.crop.y0, b.info.crop.x0);
  });
  const Part& ref = parts.front();
  for (const Part& p : parts) {
    if (p.info.full_width != ref.info.full_width || p.info.full_height != ref.info.full_height)
      throw InputError(p.file.string(), "full_resolution", fmt::format("{}x{}", p.info.full_width, p.info.full_height),
                       fmt::format("differs from {} ({}x{})", ref.file.string(), ref.info.full_width, ref.info.full_height));
    if (const auto d = signature_difference(ref.info.signature, p.info.signature))
      throw InputError(p.file.string(), d->key, d->b,
                       fmt::format("differs from {} ({} = {}): the parts of one image need the same scene file, seed and "
                                   "settings",
                                   ref.file.string(), d->key, d->a));
    if (p.info.samples() == 0) throw InputError(p.file.string(), "sample_ranges", "", "the part holds no samples");
  }
  for (size_t i = 0; i < parts.size(); ++i)
    for (size_t j = i + 1; j < parts.size(); ++j) {
      const PartInfo &a = parts[i].info, &b = parts[j].info;
      if (!a.crop.intersects(b.crop)) continue;
      for (const SampleRange& ra : a.ranges)
        for (const SampleRange& rb : b.ranges)
          if (ra.intersects(rb)) {
            const PixelWindow w{std::max(a.crop.x0, b.crop.x0), std::max(a.crop.y0, b.crop.y0), std::min(a.crop.x1, b.crop.x1),
                                std::min(a.crop.y1, b.crop.y1)};
            throw InputError(parts[j].file.string(), "sample_ranges", to_string(b.ranges),
                             fmt::format("overlaps {}: both hold samples {}:{} of pixels {} (each sample of each pixel must "
                                         "come from one part)",
                                         parts[i].file.string(), std::max(ra.begin, rb.begin), std::min(ra.end, rb.end), to_string(w)));
          }
    }

  // Coverage: cut the sample axis at every range end into elementary intervals,
  // give each a random 64-bit tag, and sum per pixel the tags of the intervals
  // its parts hold. Equal sums (and counts) mean equal sample sets.
  std::vector<int> cuts;
  for (const Part& p : parts)
    for (const SampleRange& r : p.info.ranges) cuts.insert(cuts.end(), {r.begin, r.end});
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  const int W = ref.info.full_width, H = ref.info.full_height;
  std::vector<uint64_t> tag_sum(size_t(W) * size_t(H), 0);
  std::vector<int64_t> count(tag_sum.size(), 0);
  for (const Part& p : parts) {
    uint64_t tag = 0;
    for (const SampleRange& r : p.info.ranges)
      for (size_t k = 0; k + 1 < cuts.size(); ++k)
        if (cuts[k] >= r.begin && cuts[k + 1] <= r.end) tag += mix_bits(uint64_t(k) + 0x51ed2701ULL);
    for (int y = p.info.crop.y0; y < p.info.crop.y1; ++y)
      for (int x = p.info.crop.x0; x < p.info.crop.x1; ++x) {
        tag_sum[size_t(y) * W + x] += tag;
        count[size_t(y) * W + x] += p.info.samples();
      }
  }
  auto samples_of = [&](int x, int y) {
    std::vector<SampleRange> r;
    for (const Part& p : parts)
      if (x >= p.info.crop.x0 && x < p.info.crop.x1 && y >= p.info.crop.y0 && y < p.info.crop.y1)
        r.insert(r.end(), p.info.ranges.begin(), p.info.ranges.end());
    return normalized(r);
  };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      if (count[i] == 0)
        throw InputError("command line", "PART", fmt::format("pixel ({}, {})", x, y),
                         fmt::format("no part covers this pixel of the {}x{} image: a crop is missing", W, H));
      if (count[i] != count[0] || tag_sum[i] != tag_sum[0])
        throw InputError("command line", "PART", fmt::format("pixel ({}, {})", x, y),
                         fmt::format("gets {} but pixel (0, 0) gets {}: one run gives every pixel the same samples, so a "
                                     "part is missing or extra",
                                     describe(samples_of(x, y)), describe(samples_of(0, 0))));
    }
  return samples_of(0, 0);
}

double metadata_number(const Metadata& m, std::string_view key) {
  const MetadataValue* v = m.find(key);
  if (!v) return 0;
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<int>(v)) return *i;
  return 0;
}

void set_merged_metadata(Metadata& m, const PartInfo& merged, int parts, double nonfinite, double wall_time) {
  set_part_metadata(m, merged);
  const int spp = merged.samples();
  m.set("spp", spp);
  m.set("spp_requested", spp);
  m.set("samples_per_pixel", double(spp));
  m.set("sample_first", merged.ranges.front().begin);
  m.set("nonfinite_samples", nonfinite);
  m.set("wall_time_s", wall_time);
  m.set("interrupted", 0);
  m.set("merged_parts", parts);
}

Image merge_exrs(const std::vector<std::filesystem::path>& files, MergeSummary* summary) {
  std::vector<Part> parts;
  for (const auto& f : files) parts.push_back({f, read_part_metadata(read_exr(f).metadata, f)});
  const std::vector<SampleRange> ranges = check_parts(parts);
  const int W = parts.front().info.full_width, H = parts.front().info.full_height;

  Image out;
  std::vector<std::vector<double>> acc;
  double nonfinite = 0, wall = 0;
  int64_t total = 0;
  for (const Part& p : parts) {
    Image img = read_exr(p.file);
    if (img.metadata.find("adaptive"))  // its pixels have counts of their own: the part's range does not weight them
      throw InputError(p.file.string(), "adaptive", "1", "an adaptive render (per-pixel sample counts) cannot be merged");
    const PixelWindow& c = p.info.crop;
    if (img.width != c.width() || img.height != c.height())
      throw InputError(p.file.string(), "crop", to_string(c), fmt::format("but the image is {}x{}", img.width, img.height));
    if (acc.empty()) {
      out.width = W;
      out.height = H;
      out.metadata = img.metadata;
      out.chromaticities = img.chromaticities;
      for (const ImageLayer& l : img.layers) {
        out.layers.push_back({l.name, l.channels, {}});
        acc.emplace_back(size_t(W) * size_t(H) * l.channels.size(), 0.0);
      }
    }
    if (img.layers.size() != out.layers.size())
      throw InputError(p.file.string(), "layers", std::to_string(img.layers.size()),
                       fmt::format("{} has {} layers", parts.front().file.string(), out.layers.size()));
    const double weight = p.info.samples();
    for (size_t l = 0; l < img.layers.size(); ++l) {
      const ImageLayer& src = img.layers[l];
      if (src.name != out.layers[l].name || src.channels != out.layers[l].channels)
        throw InputError(p.file.string(), "layer", src.name,
                         fmt::format("differs from layer {} ('{}') of {} (names or channels)", l, out.layers[l].name,
                                     parts.front().file.string()));
      const size_t nc = src.channels.size();
      // A standard-error layer accumulates its samples' sum of squares (film/film.h), which needs the mean.
      const ImageLayer* mean = is_stderr_layer(src.name) ? img.find_layer(stderr_base_name(src.name)) : nullptr;
      if (mean && mean->pixels.size() != src.pixels.size()) mean = nullptr;
      if (is_stderr_layer(src.name) && !mean)
        throw InputError(p.file.string(), "layer", src.name, "a standard-error layer without its mean layer");
      const bool depth_with_coverage = is_depth_layer(src);
      for (int y = 0; y < c.height(); ++y)
        for (int x = 0; x < c.width(); ++x) {
          const size_t at = (size_t(y) * c.width() + x) * nc;
          const float* s = &src.pixels[at];
          double* d = &acc[l][(size_t(c.y0 + y) * W + size_t(c.x0 + x)) * nc];
          if (depth_with_coverage) {
            // Z is the mean over the samples that hit a surface: weight it by their number, not by spp.
            const double hits = weight * double(s[1]);
            d[0] += hits > 0 ? hits * double(s[0]) : 0.0;
            d[1] += hits;
            continue;
          }
          for (size_t k = 0; k < nc; ++k) d[k] += mean ? sum_of_squares(mean->pixels[at + k], s[k], weight) : weight * double(s[k]);
        }
    }
    nonfinite += metadata_number(img.metadata, "nonfinite_samples");
    wall += metadata_number(img.metadata, "wall_time_s");
  }
  PartInfo merged = parts.front().info;
  merged.crop = {0, 0, W, H};
  merged.ranges = ranges;
  total = merged.samples();
  for (size_t l = 0; l < out.layers.size(); ++l) {
    out.layers[l].pixels.resize(acc[l].size());
    if (is_stderr_layer(out.layers[l].name)) continue;
    if (is_depth_layer(out.layers[l])) {
      for (size_t i = 0; i < acc[l].size(); i += 2) {
        out.layers[l].pixels[i] = acc[l][i + 1] > 0 ? float(acc[l][i] / acc[l][i + 1]) : std::numeric_limits<float>::infinity();
        out.layers[l].pixels[i + 1] = float(acc[l][i + 1] / double(total));
      }
      continue;
    }
    for (size_t i = 0; i < acc[l].size(); ++i) out.layers[l].pixels[i] = float(acc[l][i] / double(total));
  }
  for (size_t l = 0; l < out.layers.size(); ++l) {
    if (!is_stderr_layer(out.layers[l].name)) continue;
    const auto mean = std::find_if(out.layers.begin(), out.layers.end(),
                                   [&](const ImageLayer& m) { return m.name == stderr_base_name(out.layers[l].name); });
    const std::vector<double>& mean_sum = acc[size_t(mean - out.layers.begin())];
    for (size_t i = 0; i < acc[l].size(); ++i)
      out.layers[l].pixels[i] = float(standard_error(mean_sum[i] / double(total), acc[l][i], double(total)));
  }
  set_merged_metadata(out.metadata, merged, int(parts.size()), nonfinite, wall);
  if (summary) *summary = {int(parts.size()), int(total), ranges, false};
  return out;
}

Image merge_checkpoints(const std::vector<std::filesystem::path>& files, MergeSummary* summary) {
  std::vector<Part> parts;
  std::vector<CheckpointHeader> headers;
  for (const auto& f : files) {
    headers.push_back(read_checkpoint_header(f));
    parts.push_back({f, headers.back().part()});
  }
  const std::vector<SampleRange> ranges = check_parts(parts);
  const int W = parts.front().info.full_width, H = parts.front().info.full_height;
  std::optional<Film> full;
  double nonfinite = 0, wall = 0;
  CheckpointHeader first;
  for (const Part& p : parts) {
    CheckpointHeader h;
    const Film film = read_checkpoint(p.file, &h);
    if (!full) {
      first = h;
      full.emplace(W, H, film.layer_names(), film.color_space());
      if (film.spectral_bins() > 0) full->enable_spectral(film.spectral_min_nm(), film.spectral_max_nm(), film.spectral_bins());
      full->enable_aovs(film.aovs());
    }
    if (film.color_space() != full->color_space())
      throw InputError(p.file.string(), "color_space", "", fmt::format("differs from {}", parts.front().file.string()));
    try {
      add_film_window(*full, film, h.crop);
    } catch (const std::invalid_argument&) {
      throw InputError(p.file.string(), "layers", "",
                       fmt::format("its layers or spectral bins differ from those of {}", parts.front().file.string()));
    }
    nonfinite += double(h.nonfinite_samples);
    wall += h.wall_time_s;
  }
  PartInfo merged = parts.front().info;
  merged.crop = {0, 0, W, H};
  merged.ranges = ranges;
  Image out = full->to_image(merged.samples());
  for (const auto& [key, value] : merged.signature)
    if (key == "seed") out.metadata.set("seed", value);
  out.metadata.set("scene", first.scene);
  out.metadata.set("version", first.chlorovdb_version);
  set_merged_metadata(out.metadata, merged, int(parts.size()), nonfinite, wall);
  if (summary) *summary = {int(parts.size()), merged.samples(), ranges, true};
  return out;
}

}  // namespace

Image merge_parts(const std::vector<std::filesystem::path>& files, MergeSummary* summary) {
  size_t checkpoints = 0;
  for (const auto& f : files) {
    if (!std::filesystem::is_regular_file(f)) throw InputError(f.string(), "", "", "no such file");
    checkpoints += is_checkpoint(f);
  }
  if (checkpoints != 0 && checkpoints != files.size())
    throw InputError("command line", "PART", "",
                     "mixes checkpoints and EXR images: give all checkpoints (exact) or all EXRs (float rounding)");
  return checkpoints ? merge_checkpoints(files, summary) : merge_exrs(files, summary);
}

}  // namespace chlorovdb
