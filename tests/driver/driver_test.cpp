// The render driver in-process: crops and resumed renders are bit-identical to
// the full, uninterrupted render; sample ranges merge within double rounding;
// checkpoints round-trip exactly and refuse corrupt files.
#include <cstring>
#include <fstream>

#include <gtest/gtest.h>

#include "checkpoint/checkpoint.h"
#include "checkpoint/partition.h"
#include "core/error.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"

namespace chlorovdb {
namespace {

const std::filesystem::path kScene = std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/default.json";

Scene small_scene(int w = 24, int h = 16) {
  SceneOverrides o;
  o.width = w;
  o.height = h;
  o.wavelengths = 4;
  return load_scene(kScene, o);
}

Film make_film(const Scene& scene, int w, int h) {
  Film film(w, h, film_layer_names(), scene.settings.color_space);
  film.enable_spectral(400.f, 700.f, 6);  // exercise the spectral sums too
  return film;
}

RenderOptions options(int spp, int first = 0) {
  RenderOptions o;
  o.first_sample = first;
  o.spp = spp;
  o.seed = 11;
  o.threads = 2;
  return o;
}

void expect_identical(const Film& a, const Film& b) {
  ASSERT_EQ(a.layer_names(), b.layer_names());
  for (size_t l = 0; l < a.layer_names().size(); ++l) {
    const auto &x = a.raw_xyz(int(l)), &y = b.raw_xyz(int(l));
    ASSERT_EQ(x.size(), y.size());
    EXPECT_EQ(0, std::memcmp(x.data(), y.data(), x.size() * sizeof(double))) << "layer " << l;
  }
  ASSERT_EQ(a.raw_spectral().size(), b.raw_spectral().size());
  EXPECT_EQ(0, std::memcmp(a.raw_spectral().data(), b.raw_spectral().data(), a.raw_spectral().size() * sizeof(double)));
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

TEST(Driver, PassScheduleDependsOnlyOnSamplesDone) {
  std::vector<int> sizes;
  for (int done = 0; done < 40;) done += sizes.emplace_back(pass_size(done, 40));
  EXPECT_EQ(sizes, (std::vector<int>{1, 1, 2, 4, 8, 8, 8, 8}));
  EXPECT_EQ(pass_size(16, 20), 4);  // the last pass is cut at the total
}

TEST(Driver, ThreadCountDoesNotChangeTheSums) {
  const Scene scene = small_scene();
  Film a = make_film(scene, 24, 16), b = make_film(scene, 24, 16);
  RenderOptions o = options(3);
  o.threads = 1;
  render(scene, a, o);
  o.threads = 2;
  render(scene, b, o);
  expect_identical(a, b);
}

TEST(Driver, CropIsBitIdenticalToTheSameWindowOfTheFullRender) {
  const Scene scene = small_scene();
  Film full = make_film(scene, 24, 16);
  render(scene, full, options(4));
  const PixelWindow w{5, 3, 22, 11};
  Film crop = make_film(scene, w.width(), w.height());
  RenderOptions o = options(4);
  o.film_x0 = w.x0;
  o.film_y0 = w.y0;
  render(scene, crop, o);
  // Put the crop into an empty full-size film: equal to the full render inside the window, 0 outside.
  Film placed = make_film(scene, 24, 16);
  add_film_window(placed, crop, w);
  for (size_t l = 0; l < full.layer_names().size(); ++l)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 24; ++x)
        for (int c = 0; c < 3; ++c) {
          const size_t i = (size_t(y) * 24 + x) * 3 + c;
          const bool inside = x >= w.x0 && x < w.x1 && y >= w.y0 && y < w.y1;
          ASSERT_EQ(placed.raw_xyz(int(l))[i], inside ? full.raw_xyz(int(l))[i] : 0.0) << x << "," << y;
        }
  EXPECT_THROW(
      [&] {
        RenderOptions bad = options(1);
        bad.film_x0 = 10;  // 10 + 17 > 24
        render(scene, crop, bad);
      }(),
      std::invalid_argument);
}

TEST(Driver, ResumedFromACheckpointAtAnyPassBoundaryIsBitIdentical) {
  const Scene scene = small_scene(16, 12);
  const int spp = 20;  // passes 1, 1, 2, 4, 8, 4
  Film reference = make_film(scene, 16, 12);
  render(scene, reference, options(spp, 3));
  const auto dir = std::filesystem::temp_directory_path() / ("chlorovdb_driver_resume." + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (int stop_after : {1, 2, 4, 8, 16}) {
    SCOPED_TRACE(stop_after);
    Film film = make_film(scene, 16, 12);
    std::atomic<bool> stop{false};
    RenderOptions o = options(spp, 3);
    o.stop = &stop;
    o.on_pass = [&](int done) {
      if (done == stop_after) stop = true;
    };
    const RenderStats first = render(scene, film, o);
    ASSERT_EQ(first.samples_done, stop_after);
    ASSERT_TRUE(first.interrupted);

    CheckpointHeader h{"test", kScene.string(), 16, 12, {0, 0, 16, 12}, 3, 3 + spp, first.samples_done, {{"seed", "11"}}, 5, 1.5};
    const auto file = dir / "resume.ckpt";
    write_checkpoint(file, h, film);
    CheckpointHeader back;
    Film resumed = read_checkpoint(file, &back);
    EXPECT_EQ(back.samples_done, stop_after);
    EXPECT_EQ(back.nonfinite_samples, 5u);
    EXPECT_EQ(back.signature, h.signature);
    expect_identical(resumed, film);

    RenderOptions rest = options(spp, 3);
    rest.samples_done = back.samples_done;
    rest.threads = 1;  // another thread count on purpose
    const RenderStats second = render(scene, resumed, rest);
    EXPECT_EQ(second.samples_done, spp);
    EXPECT_FALSE(second.interrupted);
    expect_identical(resumed, reference);
  }
  std::filesystem::remove_all(dir);
}

TEST(Driver, SampleRangesAddUpToOneRunWithinDoubleRounding) {
  const Scene scene = small_scene(16, 12);
  Film whole = make_film(scene, 16, 12), a = make_film(scene, 16, 12), b = make_film(scene, 16, 12);
  render(scene, whole, options(12));
  render(scene, a, options(5, 0));
  render(scene, b, options(7, 5));
  a.merge(b);
  for (size_t l = 0; l < whole.layer_names().size(); ++l) {
    const double scale = max_abs(whole.raw_xyz(int(l)));
    for (size_t i = 0; i < whole.raw_xyz(int(l)).size(); ++i)
      ASSERT_NEAR(a.raw_xyz(int(l))[i], whole.raw_xyz(int(l))[i], 1e-12 * scale);
  }
}

TEST(Checkpoint, RefusesCorruptTruncatedAndForeignFiles) {
  const Scene scene = small_scene(8, 4);
  Film film = make_film(scene, 8, 4);
  render(scene, film, options(1));
  const auto dir = std::filesystem::temp_directory_path() / ("chlorovdb_driver_ckpt." + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "a.ckpt";
  write_checkpoint(file, {"test", "s", 8, 4, {0, 0, 8, 4}, 0, 1, 1, {}, 0, 0}, film);
  EXPECT_TRUE(is_checkpoint(file));
  EXPECT_NO_THROW(read_checkpoint(file, nullptr));
  // No temporary file is left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);

  auto expect_error = [&](const std::filesystem::path& f, const std::string& needle) {
    try {
      read_checkpoint(f, nullptr);
      ADD_FAILURE() << "no error for " << f;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
    }
  };
  const auto size = std::filesystem::file_size(file);
  const auto flipped = dir / "flipped.ckpt";
  std::filesystem::copy_file(file, flipped);
  {
    std::fstream f(flipped, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(size - 100));
    f.put('\x5a');
  }
  expect_error(flipped, "checksum");
  const auto truncated = dir / "truncated.ckpt";
  std::filesystem::copy_file(file, truncated);
  std::filesystem::resize_file(truncated, size - 8);
  expect_error(truncated, "truncated");
  const auto foreign = dir / "foreign.ckpt";
  std::ofstream(foreign) << "{\"not\": \"a checkpoint\"}";
  EXPECT_FALSE(is_checkpoint(foreign));
  expect_error(foreign, "not a chlorovdb checkpoint");
  std::filesystem::remove_all(dir);
}

TEST(Partition, ParsesCropsAndSampleRangesAndNamesBadValues) {
  EXPECT_EQ(parse_crop("0,0,10,5", 10, 5), (PixelWindow{0, 0, 10, 5}));
  EXPECT_EQ(parse_sample_range("16:48"), (SampleRange{16, 48}));
  for (const char* bad : {"0,0,11,5", "3,0,3,5", "0,0,10", "a,b,c,d", "-1,0,4,4", "0,0,4,4,"})
    EXPECT_THROW(parse_crop(bad, 10, 5), InputError) << bad;
  for (const char* bad : {"5:5", "8:4", "-1:4", "4", "0:x", "1:2:3"}) EXPECT_THROW(parse_sample_range(bad), InputError) << bad;
  try {
    parse_crop("0,0,99,5", 10, 5);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--crop"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("10x5"), std::string::npos);
  }
  EXPECT_EQ(to_string(normalized({{8, 16}, {0, 8}, {20, 24}})), "0:16,20:24");
  const auto d = signature_difference({{"seed", "1"}, {"wavelengths", "4"}}, {{"seed", "2"}});
  ASSERT_TRUE(d);
  EXPECT_EQ(d->key, "seed");
  EXPECT_EQ(d->a, "1");
  EXPECT_EQ(d->b, "2");
  EXPECT_EQ(signature_difference({{"seed", "2"}}, {{"seed", "2"}, {"wavelengths", "4"}})->a, "(missing)");
  EXPECT_FALSE(signature_difference({{"seed", "2"}}, {{"seed", "2"}}));
}

}  // namespace
}  // namespace chlorovdb
