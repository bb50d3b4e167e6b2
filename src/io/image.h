#pragma once
// Float images with named layers, written as ONE multi-channel OpenEXR through
// OpenImageIO (only io/ includes OIIO), plus an 8-bit sRGB PNG preview.
//
// EXR channel layout: the first layer's channels keep their bare names (R, G, B),
// so every viewer shows it; each further layer is stored as `<layer>.<channel>`.
// A layer named "S0" whose channels are "<λ>nm" with a decimal comma (e.g.
// "550,5nm") is an emissive spectral layer in the layout of Fichet, Pacanowski &
// Wilkie 2021 (JCGT 10(3), "An OpenEXR Layout for Spectral Images"): its channels
// become "S0.550,5nm" and the file gets that layout's spectralLayoutVersion and
// emissiveUnits attributes.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "spectra/color.h"

namespace chlorovdb {

using MetadataValue = std::variant<std::string, int, double>;

// Ordered key -> value entries, written as EXR attributes "chlorovdb:<key>".
struct Metadata {
  std::vector<std::pair<std::string, MetadataValue>> entries;

  void set(std::string key, MetadataValue value);  // replaces an existing key in place
  const MetadataValue* find(std::string_view key) const;
};

struct ImageLayer {
  std::string name;
  std::vector<std::string> channels;
  std::vector<float> pixels;  // interleaved: (y * width + x) * channels.size() + c
};

struct Image {
  int width = 0, height = 0;
  std::vector<ImageLayer> layers;
  Metadata metadata;
  // Primaries and white of the RGB channels (EXR "chromaticities" attribute), when known.
  std::optional<Chromaticities> chromaticities;

  const ImageLayer* find_layer(std::string_view name) const;
};

enum class ExrPixelType { Half, Float };

// Written to a temporary file in the same folder and renamed, so an interrupted
// write never leaves a truncated image under `path`. Throws InputError naming
// the file when it cannot be written, std::invalid_argument for an inconsistent Image.
void write_exr(const std::filesystem::path& path, const Image& image, ExrPixelType pixel_type = ExrPixelType::Float);

// Every channel, grouped back into layers by the text before the last '.'. Layers
// come in the order they were written (files from other tools: the unprefixed
// channels first, then the file's order). Returns the "chlorovdb:" attributes as
// metadata. Throws InputError naming the file when it cannot be read.
Image read_exr(const std::filesystem::path& path);

// 8-bit sRGB preview of the first three channels of `rgb` (linear): scaled by
// 2^exposure_stops, sRGB-encoded, clamped to [0, 1]. Same temp-file-and-rename write.
void write_png(const std::filesystem::path& path, const ImageLayer& rgb, int width, int height, float exposure_stops = 0.f);

}  // namespace chlorovdb
