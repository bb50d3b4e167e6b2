#include "io/image.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "core/error.h"
#include "core/temp_file.h"

namespace chlorovdb {

namespace {

constexpr std::string_view kMetadataPrefix = "chlorovdb:";
// Layer names in written order ('\n'-separated); the first one names the unprefixed channels.
constexpr const char* kLayerOrderAttribute = "chlorovdbLayers";
constexpr const char* kSpectralLayer = "S0";  // emissive, unpolarised (Stokes S0) spectral channels

// Writes through OIIO to a temporary beside `path` (temporary_beside) and renames it over `path`: rename is atomic
// within a file system, so readers see either the old file or the complete new one.
// `write(out)` writes the pixels into the opened output and returns false on failure.
template <typename WritePixels>
void write_atomically(const std::filesystem::path& path, const char* format, const OIIO::ImageSpec& spec,
                      WritePixels&& write) {
  const std::filesystem::path tmp = temporary_beside(path);
  auto fail = [&](const std::string& why) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw InputError(path.string(), "", "", fmt::format("cannot write {} image: {}", format, why));
  };
  auto out = OIIO::ImageOutput::create(format);
  if (!out) fail(OIIO::geterror());
  if (!out->open(tmp.string(), spec)) fail(out->geterror());
  if (!write(*out)) fail(out->geterror());
  if (!out->close()) fail(out->geterror());
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.message());
}

void check_layers(const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.layers.empty())
    throw std::invalid_argument(fmt::format("write_exr: empty image ({}x{}, {} layers)", image.width, image.height, image.layers.size()));
  const size_t pixel_count = size_t(image.width) * size_t(image.height);
  for (size_t l = 0; l < image.layers.size(); ++l) {
    const ImageLayer& layer = image.layers[l];
    if (layer.channels.empty()) throw std::invalid_argument(fmt::format("write_exr: layer '{}' has no channels", layer.name));
    if (layer.pixels.size() != pixel_count * layer.channels.size())
      throw std::invalid_argument(fmt::format("write_exr: layer '{}' has {} values, expected {}x{}x{}", layer.name,
                                              layer.pixels.size(), image.width, image.height, layer.channels.size()));
    if (l > 0 && (layer.name.empty() || layer.name.find('\n') != std::string::npos))
      throw std::invalid_argument(fmt::format("write_exr: layer {} needs a one-line, non-empty name", l));
    for (const std::string& c : layer.channels)
      if (c.empty() || (l == 0 && c.find('.') != std::string::npos))
        throw std::invalid_argument(fmt::format(
            "write_exr: channel '{}' of layer '{}': names must be non-empty, and the first layer's must not contain "
            "'.' (it would read back as another layer)",
            c, layer.name));
  }
}

std::vector<std::string> split_lines(std::string_view s) {
  std::vector<std::string> out;
  size_t start = 0;
  for (size_t end; (end = s.find('\n', start)) != std::string_view::npos; start = end + 1) out.emplace_back(s.substr(start, end - start));
  out.emplace_back(s.substr(start));
  return out;
}

}  // namespace

void Metadata::set(std::string key, MetadataValue value) {
  for (auto& [k, v] : entries)
    if (k == key) {
      v = std::move(value);
      return;
    }
  entries.emplace_back(std::move(key), std::move(value));
}

const MetadataValue* Metadata::find(std::string_view key) const {
  for (const auto& [k, v] : entries)
    if (k == key) return &v;
  return nullptr;
}

const ImageLayer* Image::find_layer(std::string_view name) const {
  for (const ImageLayer& l : layers)
    if (l.name == name) return &l;
  return nullptr;
}

void write_exr(const std::filesystem::path& path, const Image& image, ExrPixelType pixel_type) {
  check_layers(image);
  std::vector<std::string> names;
  std::string layer_order;
  bool spectral = false;
  for (size_t l = 0; l < image.layers.size(); ++l) {
    const ImageLayer& layer = image.layers[l];
    for (const std::string& c : layer.channels) names.push_back(l == 0 ? c : layer.name + "." + c);
    layer_order += (l ? "\n" : "") + layer.name;
    spectral = spectral || (l > 0 && layer.name == kSpectralLayer);
  }
  if (std::set<std::string>(names.begin(), names.end()).size() != names.size())
    throw std::invalid_argument(fmt::format("write_exr: {}: two layers produce the same channel name", path.string()));

  const int nchannels = int(names.size());
  OIIO::ImageSpec spec(image.width, image.height, nchannels,
                       pixel_type == ExrPixelType::Half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
  spec.channelnames = names;
  spec.attribute("compression", "zip");  // lossless
  spec.attribute(kLayerOrderAttribute, layer_order);
  if (spectral) {
    // Attributes of the spectral layout (the same values pbrt-v4's SpectralFilm writes).
    spec.attribute("spectralLayoutVersion", "1.0");
    spec.attribute("emissiveUnits", "W.m^-2.sr^-1");
  }
  if (image.chromaticities) {
    const Chromaticities& c = *image.chromaticities;
    const float xy[8] = {float(c.red_x),  float(c.red_y),  float(c.green_x), float(c.green_y),
                         float(c.blue_x), float(c.blue_y), float(c.white_x), float(c.white_y)};
    spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), xy);
  }
  for (const auto& [key, value] : image.metadata.entries) {
    const std::string name = std::string(kMetadataPrefix) + key;
    if (const auto* s = std::get_if<std::string>(&value)) spec.attribute(name, *s);
    if (const auto* i = std::get_if<int>(&value)) spec.attribute(name, *i);
    if (const auto* d = std::get_if<double>(&value)) spec.attribute(name, OIIO::TypeDesc::DOUBLE, d);
  }

  // Interleave the layers one scanline at a time: a whole interleaved copy would
  // double the image's memory at the moment a render's memory peaks.
  write_atomically(path, "openexr", spec, [&](OIIO::ImageOutput& out) {
    const size_t width = size_t(image.width);
    std::vector<float> row(width * size_t(nchannels));
    for (int y = 0; y < image.height; ++y) {
      size_t offset = 0;
      for (const ImageLayer& layer : image.layers) {
        const size_t n = layer.channels.size();
        for (size_t x = 0; x < width; ++x)
          std::copy_n(layer.pixels.begin() + (size_t(y) * width + x) * n, n, row.begin() + x * size_t(nchannels) + offset);
        offset += n;
      }
      if (!out.write_scanline(y, 0, OIIO::TypeDesc::FLOAT, row.data())) return false;
    }
    return true;
  });
}

Image read_exr(const std::filesystem::path& path) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) throw InputError(path.string(), "", "", fmt::format("cannot read image: {}", OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  const size_t nchannels = size_t(spec.nchannels);
  const size_t pixel_count = size_t(spec.width) * size_t(spec.height);
  std::vector<float> pixels(pixel_count * nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
    throw InputError(path.string(), "", "", fmt::format("cannot read pixels: {}", in->geterror()));

  Image image;
  image.width = spec.width;
  image.height = spec.height;
  const std::vector<std::string> order = split_lines(spec.get_string_attribute(kLayerOrderAttribute));
  const std::string first_layer = order.front();  // "" for files from other tools

  // Group channels by the text before the last '.'.
  std::vector<std::vector<size_t>> members;
  for (size_t c = 0; c < nchannels; ++c) {
    const std::string& full = spec.channelnames[c];
    const size_t dot = full.rfind('.');
    const std::string layer = dot == std::string::npos ? first_layer : full.substr(0, dot);
    const std::string channel = dot == std::string::npos ? full : full.substr(dot + 1);
    auto it = std::find_if(image.layers.begin(), image.layers.end(), [&](const ImageLayer& l) { return l.name == layer; });
    if (it == image.layers.end()) {
      image.layers.push_back({layer, {}, {}});
      members.emplace_back();
      it = image.layers.end() - 1;
    }
    it->channels.push_back(channel);
    members[size_t(it - image.layers.begin())].push_back(c);
  }
  for (size_t l = 0; l < image.layers.size(); ++l) {
    ImageLayer& layer = image.layers[l];
    layer.pixels.resize(pixel_count * members[l].size());
    for (size_t p = 0; p < pixel_count; ++p)
      for (size_t k = 0; k < members[l].size(); ++k) layer.pixels[p * members[l].size() + k] = pixels[p * nchannels + members[l][k]];
  }
  // Restore the written layer order; layers it does not list (other tools) keep theirs after it.
  const auto rank = [&](const ImageLayer& l) {
    const size_t i = size_t(std::find(order.begin(), order.end(), l.name) - order.begin());
    return l.name == first_layer ? size_t(0) : (i < order.size() ? i : order.size());
  };
  std::stable_sort(image.layers.begin(), image.layers.end(), [&](const ImageLayer& a, const ImageLayer& b) { return rank(a) < rank(b); });

  for (const OIIO::ParamValue& p : spec.extra_attribs) {
    const std::string name = p.name().string();
    if (name.rfind(kMetadataPrefix, 0) != 0) continue;
    const std::string key = name.substr(kMetadataPrefix.size());
    if (p.type() == OIIO::TypeDesc::INT) image.metadata.set(key, p.get_int());
    else if (p.type() == OIIO::TypeDesc::DOUBLE) image.metadata.set(key, p.get<double>());
    else if (p.type() == OIIO::TypeDesc::FLOAT) image.metadata.set(key, double(p.get_float()));
    else image.metadata.set(key, p.get_string());
  }
  if (const OIIO::ParamValue* p = spec.find_attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8))) {
    const float* xy = static_cast<const float*>(p->data());
    image.chromaticities = Chromaticities{xy[0], xy[1], xy[2], xy[3], xy[4], xy[5], xy[6], xy[7]};
  }
  return image;
}

void write_png(const std::filesystem::path& path, const ImageLayer& rgb, int width, int height, float exposure_stops) {
  const size_t n = rgb.channels.size();
  const size_t pixel_count = size_t(std::max(width, 0)) * size_t(std::max(height, 0));
  if (n < 3 || pixel_count == 0 || rgb.pixels.size() != pixel_count * n)
    throw std::invalid_argument(fmt::format("write_png: {}: layer '{}' needs 3+ channels of {}x{} pixels", path.string(),
                                            rgb.name, width, height));
  const float scale = std::exp2(exposure_stops);
  std::vector<uint8_t> bytes(pixel_count * 3);
  for (size_t p = 0; p < pixel_count; ++p)
    for (size_t c = 0; c < 3; ++c) {
      const float v = srgb_encode(rgb.pixels[p * n + c] * scale);
      bytes[p * 3 + c] = uint8_t(v > 0.f ? std::min(v, 1.f) * 255.f + 0.5f : 0.f);  // NaN -> 0
    }
  write_atomically(path, "png", OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8),
                   [&](OIIO::ImageOutput& out) { return out.write_image(OIIO::TypeDesc::UINT8, bytes.data()); });
}

}  // namespace chlorovdb
