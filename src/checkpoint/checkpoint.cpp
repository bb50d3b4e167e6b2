#include "checkpoint/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/temp_file.h"

namespace chlorovdb {

namespace {

constexpr char kMagic[8] = {'C', 'H', 'L', 'V', 'D', 'B', 'C', 'K'};
constexpr uint32_t kFormatVersion = 3;  // 2: sums of squares (standard error) after the sums; 3: AOV sums last
constexpr uint32_t kOldestReadable = 2;
static_assert(std::endian::native == std::endian::little, "checkpoints are little-endian");

// Film sums are only reachable through const accessors (film/film.h); the Film
// object itself is not const, so writing through them is well defined.
std::vector<double>& mutable_xyz(Film& film, int layer) { return const_cast<std::vector<double>&>(film.raw_xyz(layer)); }
std::vector<double>& mutable_rgb2(Film& film, int layer) { return const_cast<std::vector<double>&>(film.raw_rgb_squares(layer)); }
std::vector<double>& mutable_spectral(Film& film) { return const_cast<std::vector<double>&>(film.raw_spectral()); }
std::vector<double>& mutable_aovs(Film& film) { return const_cast<std::vector<double>&>(film.raw_aovs()); }

// Word-wise 64-bit hash (FNV-style multiply-xor with a final mix): catches torn or corrupted files.
struct Checksum {
  uint64_t h = 0xcbf29ce484222325ULL;
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (; i + 8 <= bytes; i += 8) {
      uint64_t w;
      std::memcpy(&w, p + i, 8);
      h = (h ^ w) * 0x100000001b3ULL;
      h ^= h >> 29;
    }
    for (; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
  }
};

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

const char* color_space_name(ColorSpace c) { return c == ColorSpace::sRGB ? "sRGB" : "ACEScg"; }

nlohmann::json header_json(const CheckpointHeader& h, const Film& film) {
  nlohmann::json j;
  j["chlorovdb_version"] = h.chlorovdb_version;
  j["scene"] = h.scene;
  j["full_resolution"] = {h.full_width, h.full_height};
  j["crop"] = {h.crop.x0, h.crop.y0, h.crop.x1, h.crop.y1};
  j["sample_first"] = h.sample_first;
  j["sample_end"] = h.sample_end;
  j["samples_done"] = h.samples_done;
  nlohmann::json sig = nlohmann::json::array();
  for (const auto& [k, v] : h.signature) sig.push_back({k, v});
  j["signature"] = sig;
  j["nonfinite_samples"] = h.nonfinite_samples;
  j["wall_time_s"] = h.wall_time_s;
  j["layers"] = film.layer_names();
  j["color_space"] = color_space_name(film.color_space());
  j["spectral"] = {{"min_nm", film.spectral_min_nm()}, {"max_nm", film.spectral_max_nm()}, {"bins", film.spectral_bins()}};
  j["aovs"] = aov_list(film.aovs());
  return j;
}

size_t payload_doubles(int w, int h, size_t layers, int bins, AovMask aovs) {
  return size_t(w) * size_t(h) * (6 * layers + size_t(bins) + (aovs ? Film::kAovSums : 0));
}

struct Parsed {
  CheckpointHeader header;
  std::vector<std::string> layers;
  ColorSpace color_space = ColorSpace::sRGB;
  float spectral_min = 0, spectral_max = 0;
  int bins = 0;
  AovMask aovs = 0;
  uint64_t header_bytes = 0;  // offset of the payload
  Checksum checksum;          // over everything up to the payload
};

Parsed parse(std::FILE* f, const std::filesystem::path& file) {
  auto bad = [&](std::string_view key, std::string_view value, std::string_view problem) {
    return InputError(file.string(), key, value, problem);
  };
  Parsed p;
  char magic[8];
  uint32_t version = 0;
  uint64_t length = 0;
  if (std::fread(magic, 1, 8, f) != 8 || std::memcmp(magic, kMagic, 8) != 0)
    throw bad("", "", "not a chlorovdb checkpoint (missing the CHLVDBCK magic)");
  if (std::fread(&version, 4, 1, f) != 1 || version < kOldestReadable || version > kFormatVersion)
    throw bad("format version", std::to_string(version),
              fmt::format("this build reads versions {} to {}", kOldestReadable, kFormatVersion));
  if (std::fread(&length, 8, 1, f) != 1 || length > (64u << 20)) throw bad("header length", std::to_string(length), "truncated or corrupt");
  std::string text(length, '\0');
  if (std::fread(text.data(), 1, length, f) != length) throw bad("header", "", "truncated file");
  p.checksum.add(magic, 8);
  p.checksum.add(&version, 4);
  p.checksum.add(&length, 8);
  p.checksum.add(text.data(), text.size());
  p.header_bytes = 20 + length;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    CheckpointHeader& h = p.header;
    h.chlorovdb_version = j.at("chlorovdb_version").get<std::string>();
    h.scene = j.at("scene").get<std::string>();
    h.full_width = j.at("full_resolution").at(0).get<int>();
    h.full_height = j.at("full_resolution").at(1).get<int>();
    const auto& c = j.at("crop");
    h.crop = {c.at(0).get<int>(), c.at(1).get<int>(), c.at(2).get<int>(), c.at(3).get<int>()};
    h.sample_first = j.at("sample_first").get<int>();
    h.sample_end = j.at("sample_end").get<int>();
    h.samples_done = j.at("samples_done").get<int>();
    for (const auto& e : j.at("signature")) h.signature.emplace_back(e.at(0).get<std::string>(), e.at(1).get<std::string>());
    h.nonfinite_samples = j.at("nonfinite_samples").get<uint64_t>();
    h.wall_time_s = j.at("wall_time_s").get<double>();
    p.layers = j.at("layers").get<std::vector<std::string>>();
    const std::string cs = j.at("color_space").get<std::string>();
    if (cs != "sRGB" && cs != "ACEScg") throw bad("color_space", cs, "expected sRGB or ACEScg");
    p.color_space = cs == "sRGB" ? ColorSpace::sRGB : ColorSpace::ACEScg;
    p.spectral_min = j.at("spectral").at("min_nm").get<float>();
    p.spectral_max = j.at("spectral").at("max_nm").get<float>();
    p.bins = j.at("spectral").at("bins").get<int>();
    if (version >= 3) {
      std::string unknown;
      p.aovs = aov_mask(j.at("aovs").get<std::vector<std::string>>(), &unknown);
      if (!unknown.empty()) throw bad("aovs", unknown, "not an AOV this build knows");
    }
  } catch (const nlohmann::json::exception& e) {
    throw bad("header", "", fmt::format("corrupt JSON header: {}", e.what()));
  }
  const CheckpointHeader& h = p.header;
  if (h.full_width < 1 || h.full_height < 1 || h.crop.empty() || h.crop.x0 < 0 || h.crop.y0 < 0 || h.crop.x1 > h.full_width ||
      h.crop.y1 > h.full_height)
    throw bad("crop", to_string(h.crop), fmt::format("not a window of the {}x{} image", h.full_width, h.full_height));
  if (h.sample_first < 0 || h.samples_done < 0 || h.sample_end < h.sample_first + h.samples_done)
    throw bad("samples", fmt::format("first {}, done {}, end {}", h.sample_first, h.samples_done, h.sample_end), "inconsistent");
  if (p.layers.empty() || p.bins < 0) throw bad("layers", "", "no layers or negative spectral bins");
  return p;
}

void fail_write(const std::filesystem::path& file, const std::filesystem::path& tmp, const std::string& why) {
  std::error_code ignored;
  std::filesystem::remove(tmp, ignored);
  throw InputError(file.string(), "", "", fmt::format("cannot write checkpoint: {}", why));
}

}  // namespace

PartInfo CheckpointHeader::part() const {
  PartInfo p;
  p.full_width = full_width;
  p.full_height = full_height;
  p.crop = crop;
  if (samples_done > 0) p.ranges.push_back({sample_first, sample_first + samples_done});
  p.signature = signature;
  return p;
}

void write_checkpoint(const std::filesystem::path& file, const CheckpointHeader& header, const Film& film) {
  if (film.width() != header.crop.width() || film.height() != header.crop.height())
    throw std::invalid_argument(fmt::format("write_checkpoint: film {}x{} but crop {}", film.width(), film.height(), to_string(header.crop)));
  const std::string text = header_json(header, film).dump();
  const std::filesystem::path tmp = temporary_beside(file);
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
  }
  File f(std::fopen(tmp.c_str(), "wb"));
  if (!f) fail_write(file, tmp, std::strerror(errno));
  Checksum sum;
  auto put = [&](const void* data, size_t bytes) {
    if (bytes && std::fwrite(data, 1, bytes, f.get()) != bytes) fail_write(file, tmp, std::strerror(errno));
    sum.add(data, bytes);
  };
  const uint32_t version = kFormatVersion;
  const uint64_t length = text.size();
  put(kMagic, 8);
  put(&version, 4);
  put(&length, 8);
  put(text.data(), text.size());
  for (size_t l = 0; l < film.layer_names().size(); ++l) put(film.raw_xyz(int(l)).data(), film.raw_xyz(int(l)).size() * 8);
  for (size_t l = 0; l < film.layer_names().size(); ++l)
    put(film.raw_rgb_squares(int(l)).data(), film.raw_rgb_squares(int(l)).size() * 8);
  put(film.raw_spectral().data(), film.raw_spectral().size() * 8);
  put(film.raw_aovs().data(), film.raw_aovs().size() * 8);
  const uint64_t checksum = sum.h;
  if (std::fwrite(&checksum, 8, 1, f.get()) != 1 || std::fflush(f.get()) != 0 || ::fsync(::fileno(f.get())) != 0)
    fail_write(file, tmp, std::strerror(errno));
  if (std::fclose(f.release()) != 0) fail_write(file, tmp, std::strerror(errno));
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) fail_write(file, tmp, ec.message());
  // Make the rename itself durable.
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  if (const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY); fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

bool is_checkpoint(const std::filesystem::path& file) {
  File f(std::fopen(file.c_str(), "rb"));
  char magic[8];
  return f && std::fread(magic, 1, 8, f.get()) == 8 && std::memcmp(magic, kMagic, 8) == 0;
}

CheckpointHeader read_checkpoint_header(const std::filesystem::path& file) {
  File f(std::fopen(file.c_str(), "rb"));
  if (!f) throw InputError(file.string(), "", "", fmt::format("cannot open checkpoint: {}", std::strerror(errno)));
  return parse(f.get(), file).header;
}

Film read_checkpoint(const std::filesystem::path& file, CheckpointHeader* header) {
  File f(std::fopen(file.c_str(), "rb"));
  if (!f) throw InputError(file.string(), "", "", fmt::format("cannot open checkpoint: {}", std::strerror(errno)));
  Parsed p = parse(f.get(), file);
  const int w = p.header.crop.width(), h = p.header.crop.height();
  std::error_code ec;
  const uint64_t expected = p.header_bytes + 8 * payload_doubles(w, h, p.layers.size(), p.bins, p.aovs) + 8;
  const uint64_t actual = std::filesystem::file_size(file, ec);
  if (ec || actual != expected)
    throw InputError(file.string(), "size", std::to_string(actual),
                     fmt::format("expected {} bytes for its header: truncated or corrupt", expected));
  Film film(w, h, p.layers, p.color_space);
  if (p.bins > 0) film.enable_spectral(p.spectral_min, p.spectral_max, p.bins);
  film.enable_aovs(p.aovs);
  auto get = [&](std::vector<double>& v) {
    if (!v.empty() && std::fread(v.data(), 8, v.size(), f.get()) != v.size())
      throw InputError(file.string(), "sums", "", "truncated file");
    p.checksum.add(v.data(), v.size() * 8);
  };
  for (size_t l = 0; l < p.layers.size(); ++l) get(mutable_xyz(film, int(l)));
  for (size_t l = 0; l < p.layers.size(); ++l) get(mutable_rgb2(film, int(l)));
  get(mutable_spectral(film));
  get(mutable_aovs(film));
  uint64_t stored = 0;
  if (std::fread(&stored, 8, 1, f.get()) != 1 || stored != p.checksum.h)
    throw InputError(file.string(), "checksum", fmt::format("{:016x}", stored), "does not match the contents: corrupt file");
  if (header) *header = std::move(p.header);
  return film;
}

void add_film_window(Film& full, const Film& part, const PixelWindow& window) {
  if (part.width() != window.width() || part.height() != window.height() || window.x0 < 0 || window.y0 < 0 ||
      window.x1 > full.width() || window.y1 > full.height() || part.layer_names() != full.layer_names() ||
      part.spectral_bins() != full.spectral_bins() || part.spectral_min_nm() != full.spectral_min_nm() ||
      part.spectral_max_nm() != full.spectral_max_nm() || part.aovs() != full.aovs())
    throw std::invalid_argument(fmt::format("add_film_window: a {}x{} film with {} layers and {} bins does not fit window {} of a "
                                            "{}x{} film with {} layers and {} bins",
                                            part.width(), part.height(), part.layer_names().size(), part.spectral_bins(),
                                            to_string(window), full.width(), full.height(), full.layer_names().size(),
                                            full.spectral_bins()));
  auto add_rows = [&](std::vector<double>& dst, const std::vector<double>& src, size_t per_pixel) {
    for (int y = 0; y < window.height(); ++y) {
      const size_t d = (size_t(window.y0 + y) * size_t(full.width()) + size_t(window.x0)) * per_pixel;
      const size_t s = size_t(y) * size_t(window.width()) * per_pixel;
      for (size_t i = 0; i < size_t(window.width()) * per_pixel; ++i) dst[d + i] += src[s + i];
    }
  };
  for (size_t l = 0; l < full.layer_names().size(); ++l) {
    add_rows(mutable_xyz(full, int(l)), part.raw_xyz(int(l)), 3);
    add_rows(mutable_rgb2(full, int(l)), part.raw_rgb_squares(int(l)), 3);
  }
  if (full.spectral_bins() > 0) add_rows(mutable_spectral(full), part.raw_spectral(), size_t(full.spectral_bins()));
  if (full.aovs()) add_rows(mutable_aovs(full), part.raw_aovs(), Film::kAovSums);
}

namespace {
void overwrite(std::vector<double>& dst, const std::vector<double>& sums, const char* what) {
  if (sums.size() != dst.size()) throw std::invalid_argument(fmt::format("{}: size mismatch", what));
  dst = sums;
}
}  // namespace

void set_raw_sums(Film& film, int layer, const std::vector<double>& sums) { overwrite(mutable_xyz(film, layer), sums, "set_raw_sums"); }
void set_raw_rgb_squares(Film& film, int layer, const std::vector<double>& sums) {
  overwrite(mutable_rgb2(film, layer), sums, "set_raw_rgb_squares");
}
void set_raw_spectral(Film& film, const std::vector<double>& sums) { overwrite(mutable_spectral(film), sums, "set_raw_spectral"); }
void set_raw_aovs(Film& film, const std::vector<double>& sums) { overwrite(mutable_aovs(film), sums, "set_raw_aovs"); }

}  // namespace chlorovdb
