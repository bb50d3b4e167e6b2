#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <thread>
#include <atomic>

#include "core/error.h"
#include "io/image.h"

using namespace chlorovdb;

namespace {

std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("chlorovdb_io_test_" + std::to_string(::getpid()) + "_" + name);
}

ImageLayer make_layer(std::string name, std::vector<std::string> channels, int w, int h, float seed) {
  ImageLayer l{std::move(name), std::move(channels), {}};
  l.pixels.resize(size_t(w) * h * l.channels.size());
  // Values that need every float bit (not representable in half).
  for (size_t i = 0; i < l.pixels.size(); ++i) l.pixels[i] = seed + std::sin(float(i) * 0.7f) * 1.2345678f + 1e-7f * float(i);
  return l;
}

Image make_image() {
  Image img;
  img.width = 5;
  img.height = 3;
  img.layers.push_back(make_layer("beauty", {"R", "G", "B"}, 5, 3, 1.f));
  img.layers.push_back(make_layer("fluorescence", {"R", "G", "B"}, 5, 3, 2.f));
  img.layers.push_back(make_layer("S0", {"400nm", "550,5nm", "700nm"}, 5, 3, 3.f));
  img.layers.push_back(make_layer("albedo", {"Y"}, 5, 3, 4.f));
  img.metadata.set("scene", std::string("scenes/cuvette.json"));
  img.metadata.set("samples_per_pixel", 64);
  img.metadata.set("render_time_s", 12.375);
  img.chromaticities = kAcesCgChromaticities;
  return img;
}

bool bit_equal(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(Exr, RoundTripIsBitExactForFloat) {
  const Image img = make_image();
  const auto path = temp_path("roundtrip.exr");
  write_exr(path, img);
  const Image back = read_exr(path);
  std::filesystem::remove(path);

  EXPECT_EQ(back.width, img.width);
  EXPECT_EQ(back.height, img.height);
  ASSERT_EQ(back.layers.size(), img.layers.size());
  for (size_t l = 0; l < img.layers.size(); ++l) {
    const ImageLayer& a = img.layers[l];
    const ImageLayer& b = back.layers[l];
    EXPECT_EQ(b.name, a.name);  // order and names restored
    ASSERT_EQ(b.channels, a.channels) << a.name;
    ASSERT_EQ(b.pixels.size(), a.pixels.size());
    for (size_t i = 0; i < a.pixels.size(); ++i) ASSERT_TRUE(bit_equal(a.pixels[i], b.pixels[i])) << a.name << " " << i;
  }
  ASSERT_NE(back.metadata.find("scene"), nullptr);
  EXPECT_EQ(std::get<std::string>(*back.metadata.find("scene")), "scenes/cuvette.json");
  EXPECT_EQ(std::get<int>(*back.metadata.find("samples_per_pixel")), 64);
  EXPECT_EQ(std::get<double>(*back.metadata.find("render_time_s")), 12.375);
  ASSERT_TRUE(back.chromaticities.has_value());
  EXPECT_FLOAT_EQ(float(back.chromaticities->red_x), 0.713f);
  EXPECT_FLOAT_EQ(float(back.chromaticities->white_y), 0.33767f);
}

TEST(Exr, FileChannelNamesFollowTheLayerAndSpectralConventions) {
  const auto path = temp_path("names.exr");
  write_exr(path, make_image());
  auto in = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(in);
  const std::vector<std::string>& names = in->spec().channelnames;
  for (const char* expected : {"R", "G", "B", "fluorescence.R", "S0.400nm", "S0.550,5nm", "albedo.Y"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  EXPECT_EQ(in->spec().get_string_attribute("spectralLayoutVersion"), "1.0");
  in->close();
  std::filesystem::remove(path);
}

TEST(Exr, HalfPixelsRoundToHalfPrecision) {
  Image img = make_image();
  const auto path = temp_path("half.exr");
  write_exr(path, img, ExrPixelType::Half);
  const Image back = read_exr(path);
  std::filesystem::remove(path);
  for (size_t i = 0; i < img.layers[0].pixels.size(); ++i)
    EXPECT_NEAR(back.layers[0].pixels[i], img.layers[0].pixels[i], 1e-3f * std::fabs(img.layers[0].pixels[i]));
}

TEST(Exr, NoTemporaryFileIsLeftBehind) {
  const auto dir = temp_path("dir");
  std::filesystem::create_directories(dir);
  write_exr(dir / "a.exr", make_image());
  write_exr(dir / "a.exr", make_image());  // overwrite in place
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}

TEST(Exr, ErrorsNameTheFile) {
  try {
    write_exr("/nonexistent-dir/out.exr", make_image());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/out.exr"), std::string::npos) << e.what();
  }
  try {
    read_exr("/nonexistent-dir/in.exr");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/in.exr"), std::string::npos) << e.what();
  }
}

TEST(Exr, InconsistentImagesAreRejected) {
  Image img = make_image();
  img.layers[1].pixels.pop_back();
  EXPECT_THROW(write_exr(temp_path("bad.exr"), img), std::invalid_argument);
  img = make_image();
  img.layers[2].name = "fluorescence";
  img.layers[2].channels = {"R", "G", "B"};
  EXPECT_THROW(write_exr(temp_path("bad.exr"), img), std::invalid_argument);  // duplicate channel names
}

TEST(Png, WrittenAndReadable) {
  ImageLayer rgb{"beauty", {"R", "G", "B"}, {0.f, 0.5f, 1.f, 0.25f, 4.f, std::numeric_limits<float>::quiet_NaN()}};
  const auto path = temp_path("preview.png");
  write_png(path, rgb, 2, 1, 1.f);  // +1 stop: values doubled
  auto in = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().width, 2);
  EXPECT_EQ(in->spec().height, 1);
  ASSERT_EQ(in->spec().nchannels, 3);
  unsigned char px[6];
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px));
  in->close();
  std::filesystem::remove(path);
  EXPECT_EQ(px[0], 0);
  EXPECT_EQ(px[1], 255);  // 2 * 0.5 = 1
  EXPECT_EQ(px[2], 255);  // clamped
  EXPECT_EQ(px[3], 188);  // srgb_encode(0.5) = 0.7354
  EXPECT_EQ(px[4], 255);
  EXPECT_EQ(px[5], 0);  // NaN -> black
}

TEST(Png, UnwritablePathIsNamed) {
  ImageLayer rgb{"beauty", {"R", "G", "B"}, {0.f, 0.5f, 1.f}};
  try {
    write_png("/nonexistent-dir/preview.png", rgb, 1, 1);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/preview.png"), std::string::npos) << e.what();
  }
}

// Threads of one process writing one path at once (as two renders of a
// library caller would): each write has its own temporary, so a reader only
// ever sees a whole image, and no temporary is left behind.
TEST(ExrWrite, ConcurrentWritersInOneProcessNeverTearTheFile) {
  const auto dir = temp_path("concurrent");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto path = dir / "same.exr";
  Image a = make_image(), b = make_image();
  for (float& v : b.layers[0].pixels) v += 100.f;
  write_exr(path, a);
  std::atomic<bool> done{false};
  std::atomic<int> torn{0};
  std::thread reader([&] {
    while (!done) {
      try {
        const Image r = read_exr(path);
        const float first = r.layers.at(0).pixels.at(0);
        if (first != a.layers[0].pixels[0] && first != b.layers[0].pixels[0]) ++torn;
      } catch (const std::exception&) {
        ++torn;  // unreadable: torn or missing
      }
    }
  });
  std::vector<std::thread> writers;
  for (const Image* img : {&a, &b})
    writers.emplace_back([&, img] {
      for (int i = 0; i < 40; ++i) write_exr(path, *img);
    });
  for (auto& w : writers) w.join();
  done = true;
  reader.join();
  EXPECT_EQ(torn, 0);
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(e.path(), path);
  }
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}
