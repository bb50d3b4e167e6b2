// `chlorovdb render` / `merge` as a user runs them, in child processes: a render
// killed with SIGKILL resumes from its checkpoint to the same image as an
// uninterrupted run; Ctrl-C writes the image and a checkpoint; crops and sample
// ranges merge into the single-run image; bad combinations are refused.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "checkpoint/checkpoint.h"
#include "child_process.h"
#include "io/image.h"
#include "media/medium.h"

namespace chlorovdb::test {
namespace {

const std::string kExe = CHLOROVDB_EXE;
// The default scene with a spectral layer, so every kind of layer is checked.
std::string scene_file() {
  static const std::string path = [] {
    std::string json = read_text(std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/default.json");
    const std::string key = "\"render\": {";
    const size_t at = json.find(key);
    EXPECT_NE(at, std::string::npos);
    json.insert(at + key.size(), "\"spectral_bins\": 6, ");
    const auto file = std::filesystem::temp_directory_path() / ("chlorovdb_driver_scene." + std::to_string(::getpid()) + ".json");
    std::ofstream(file) << json;
    return file.string();
  }();
  return path;
}

std::vector<std::string> render_args(const std::filesystem::path& out, std::vector<std::string> extra, std::string seed = "3") {
  std::vector<std::string> a = {kExe, "render", scene_file(), "-o", out.string(), "--resolution", "32x24", "--wavelengths", "4",
                                "--seed", seed, "--threads", "2", "-q"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

int metadata_int(const Image& img, const char* key) {
  const MetadataValue* v = img.metadata.find(key);
  return v && std::holds_alternative<int>(*v) ? std::get<int>(*v) : -1;
}

void expect_same_pixels(const Image& a, const Image& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.layers.size(), b.layers.size());
  for (size_t l = 0; l < a.layers.size(); ++l) {
    ASSERT_EQ(a.layers[l].channels, b.layers[l].channels);
    ASSERT_EQ(a.layers[l].pixels.size(), b.layers[l].pixels.size());
    EXPECT_EQ(0, std::memcmp(a.layers[l].pixels.data(), b.layers[l].pixels.data(), a.layers[l].pixels.size() * sizeof(float)))
        << "layer " << a.layers[l].name;
  }
}

// Equal within float rounding: each part's mean was rounded to float once.
void expect_close_pixels(const Image& a, const Image& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.layers.size(), b.layers.size());
  for (size_t l = 0; l < a.layers.size(); ++l) {
    const auto &x = a.layers[l].pixels, &y = b.layers[l].pixels;
    ASSERT_EQ(a.layers[l].name, b.layers[l].name);
    ASSERT_EQ(x.size(), y.size());
    float scale = 0;
    for (float v : y) scale = std::max(scale, std::abs(v));
    for (size_t i = 0; i < x.size(); ++i)
      ASSERT_NEAR(x[i], y[i], 4e-7f * std::max(std::abs(x[i]), std::abs(y[i])) + 1e-6f * scale)
          << "layer " << a.layers[l].name << " value " << i;
  }
}

void expect_identical_sums(const std::filesystem::path& a, const std::filesystem::path& b) {
  CheckpointHeader ha, hb;
  const Film fa = read_checkpoint(a, &ha), fb = read_checkpoint(b, &hb);
  EXPECT_EQ(ha.samples_done, hb.samples_done);
  for (size_t l = 0; l < fa.layer_names().size(); ++l)
    EXPECT_TRUE(fa.raw_xyz(int(l)) == fb.raw_xyz(int(l))) << "layer " << l;  // bitwise for finite doubles
  for (size_t l = 0; l < fa.layer_names().size(); ++l)
    EXPECT_TRUE(fa.raw_rgb_squares(int(l)) == fb.raw_rgb_squares(int(l))) << "squares, layer " << l;
  EXPECT_TRUE(fa.raw_spectral() == fb.raw_spectral());
}

TEST(RenderCli, KilledRenderResumesToTheUninterruptedImage) {
  const TestDir dir;
  const int spp = 400;  // passes 1, 1, 2, 4, 8, ...: a checkpoint after every one; ~2 s of rendering to kill it in
  const std::string spp_arg = std::to_string(spp);

  // The uninterrupted run.
  const auto ref = run(render_args(dir / "ref.exr", {"--spp", spp_arg, "--checkpoint", (dir / "ref.ckpt").string()}), dir / "ref.log");
  ASSERT_EQ(ref.status, 0) << ref.output;

  // SIGKILL once the first checkpoint is on disk, then resume.
  const auto ckpt = dir / "killed.ckpt";
  const Child c = spawn(render_args(dir / "resumed.exr", {"--spp", spp_arg, "--checkpoint", ckpt.string(), "--checkpoint-every", "0"}),
                        dir / "killed.log");
  ASSERT_TRUE(wait_for_file(c, ckpt, std::chrono::seconds(60))) << read_text(dir / "killed.log");
  // A few passes in (the rename is atomic, so reading while it writes is safe), unless it runs too fast to catch.
  for (int i = 0; i < 500 && read_checkpoint_header(ckpt).samples_done < 24; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ::kill(c.pid, SIGKILL);
  EXPECT_EQ(wait_for(c), 128 + SIGKILL);
  const CheckpointHeader at_kill = read_checkpoint_header(ckpt);
  ASSERT_GT(at_kill.samples_done, 0);
  ASSERT_LT(at_kill.samples_done, spp) << "the render finished before it was killed: raise spp";
  EXPECT_FALSE(std::filesystem::exists(dir / "resumed.exr"));

  // Without --resume an existing checkpoint is never overwritten.
  const auto clobber = run(render_args(dir / "resumed.exr", {"--spp", spp_arg, "--checkpoint", ckpt.string()}), dir / "clobber.log");
  EXPECT_EQ(clobber.status, 1);
  EXPECT_NE(clobber.output.find("--resume"), std::string::npos) << clobber.output;

  // Resuming with another seed (or size) is refused, naming what differs.
  const auto other_seed = run(render_args(dir / "resumed.exr", {"--spp", spp_arg, "--checkpoint", ckpt.string(), "--resume"}, "4"),
                              dir / "seed.log");
  EXPECT_EQ(other_seed.status, 1);
  EXPECT_NE(other_seed.output.find("rendered with seed = 3, this render has seed = 4"), std::string::npos) << other_seed.output;
  EXPECT_NE(other_seed.output.find("refusing to resume"), std::string::npos) << other_seed.output;
  auto other_size = render_args(dir / "resumed.exr", {"--spp", spp_arg, "--checkpoint", ckpt.string(), "--resume"});
  other_size[6] = "33x24";
  const auto size_run = run(other_size, dir / "size.log");
  EXPECT_EQ(size_run.status, 1);
  EXPECT_NE(size_run.output.find("resolution = 32x24"), std::string::npos) << size_run.output;

  const auto resumed = run(render_args(dir / "resumed.exr", {"--spp", spp_arg, "--checkpoint", ckpt.string(), "--resume"}),
                           dir / "resumed.log");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming"), std::string::npos) << resumed.output;

  expect_identical_sums(ckpt, dir / "ref.ckpt");
  const Image a = read_exr(dir / "resumed.exr"), b = read_exr(dir / "ref.exr");
  expect_same_pixels(a, b);
  EXPECT_EQ(metadata_int(a, "spp"), spp);
  EXPECT_EQ(metadata_int(a, "resumed_at_spp"), at_kill.samples_done);
}

TEST(RenderCli, InterruptWritesTheImageAndACheckpointThatResumes) {
  const TestDir dir;
  const auto ckpt = dir / "int.ckpt";
  const Child c = spawn(render_args(dir / "int.exr", {"--spp", "400", "--checkpoint", ckpt.string(), "--checkpoint-every", "0"}),
                        dir / "int.log");
  ASSERT_TRUE(wait_for_file(c, ckpt, std::chrono::seconds(60))) << read_text(dir / "int.log");
  ::kill(c.pid, SIGINT);
  EXPECT_EQ(wait_for(c), 130) << read_text(dir / "int.log");
  const Image img = read_exr(dir / "int.exr");
  EXPECT_EQ(metadata_int(img, "interrupted"), 1);
  const CheckpointHeader h = read_checkpoint_header(ckpt);
  EXPECT_EQ(h.samples_done, metadata_int(img, "spp")) << "the checkpoint holds the passes the image shows";
  EXPECT_LT(h.samples_done, 400);

  // Resumed to the end: the same image as an uninterrupted run.
  const auto resumed = run(render_args(dir / "int.exr", {"--spp", "400", "--checkpoint", ckpt.string(), "--resume"}), dir / "resumed.log");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  const auto ref = run(render_args(dir / "ref.exr", {"--spp", "400"}), dir / "ref.log");
  ASSERT_EQ(ref.status, 0) << ref.output;
  expect_same_pixels(read_exr(dir / "int.exr"), read_exr(dir / "ref.exr"));
}

// The metadata names the majorant cell size each grid medium chose: benchmarks compare it.
TEST(RenderCli, MetadataNamesTheMajorantCellSize) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/leaf_D65.json").string();
  const auto r = run({kExe, "render", scene, "-o", (dir / "leaf.exr").string(), "--resolution", "8x8", "--spp", "1", "-q"},
                     dir / "leaf.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const Image img = read_exr(dir / "leaf.exr");
  const MetadataValue* v = img.metadata.find("majorant_cell_voxels");
  ASSERT_NE(v, nullptr);
  ASSERT_TRUE(std::holds_alternative<std::string>(*v));
  const int size = std::stoi(std::get<std::string>(*v));
  EXPECT_NE(std::find(kMajorantCellSizes.begin(), kMajorantCellSizes.end(), size), kMajorantCellSizes.end());
}

std::string metadata_text(const Image& img, const char* key) {
  const MetadataValue* v = img.metadata.find(key);
  return v && std::holds_alternative<std::string>(*v) ? std::get<std::string>(*v) : "";
}

// --target-error stops at the first power-of-two look (>= 16 spp) that meets it;
// --time-limit after the first pass past the limit; both exit 0 and say why.
TEST(RenderCli, TargetErrorAndTimeLimitStopEarly) {
  const TestDir dir;
  auto r = run(render_args(dir / "easy.exr", {"--target-error", "100", "--spp", "64"}), dir / "easy.log");
  ASSERT_EQ(r.status, 0) << r.output;
  Image img = read_exr(dir / "easy.exr");
  EXPECT_EQ(metadata_int(img, "spp"), 16);
  EXPECT_EQ(metadata_text(img, "stop_reason"), "target error reached");
  ASSERT_NE(img.find_layer("total_stderr"), nullptr);
  r = run(render_args(dir / "hard.exr", {"--target-error", "1e-6", "--spp", "20", "--target-region", "0,0,8,8"}), dir / "hard.log");
  ASSERT_EQ(r.status, 0) << r.output;
  img = read_exr(dir / "hard.exr");
  EXPECT_EQ(metadata_int(img, "spp"), 20);
  EXPECT_EQ(metadata_text(img, "stop_reason"), "none");
  ASSERT_NE(img.metadata.find("relative_error"), nullptr);
  r = run(render_args(dir / "quick.exr", {"--time-limit", "0", "--spp", "64"}), dir / "quick.log");
  ASSERT_EQ(r.status, 0) << r.output;
  img = read_exr(dir / "quick.exr");
  EXPECT_EQ(metadata_int(img, "spp"), 1);
  EXPECT_EQ(metadata_text(img, "stop_reason"), "time limit reached");
  r = run(render_args(dir / "bad.exr", {"--target-error", "0.1", "--target-region", "0,0,99,8"}), dir / "bad.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("--target-region"), std::string::npos) << r.output;
}

TEST(MeasureCli, PrintsIntervalsAndWritesCsv) {
  const TestDir dir;
  const auto r = run({kExe, "measure", scene_file(), "--region", "10,8,14,12", "--resolution", "32x24", "--spp", "8", "--batches", "4",
                      "--bands", "5", "--threads", "2", "--csv", (dir / "m.csv").string()},
                     dir / "m.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("W m^-2 sr^-1 nm^-1"), std::string::npos) << r.output;
  const std::string csv = read_text(dir / "m.csv");
  EXPECT_EQ(csv.rfind("quantity,layer,channel,wavelength_nm,unit,mean,half_width", 0), 0u) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 1 + 3 * 6 + 5) << csv;
}

TEST(MergeCli, TwoSampleRangesAndTwoCropsMergeToTheSingleRun) {
  const TestDir dir;
  const auto ref = run(render_args(dir / "single.exr", {"--spp", "16", "--checkpoint", (dir / "single.ckpt").string()}), dir / "single.log");
  ASSERT_EQ(ref.status, 0) << ref.output;
  // Samples 0:8 of the whole image; samples 8:16 as a left and a right crop.
  const std::vector<std::pair<std::string, std::vector<std::string>>> parts = {
      {"a", {"--sample-range", "0:8"}},
      {"b", {"--sample-range", "8:16", "--crop", "0,0,13,24"}},
      {"c", {"--sample-range", "8:16", "--crop", "13,0,32,24"}},
  };
  for (const auto& [name, extra] : parts) {
    std::vector<std::string> args = extra;
    args.insert(args.end(), {"--checkpoint", (dir / (name + ".ckpt")).string()});
    const auto r = run(render_args(dir / (name + ".exr"), args), dir / (name + ".log"));
    ASSERT_EQ(r.status, 0) << r.output;
  }
  const Image crop = read_exr(dir / "b.exr");
  EXPECT_EQ(crop.width, 13);
  EXPECT_EQ(crop.height, 24);

  // EXR parts (listed out of order on purpose): float means weighted by samples.
  const auto merged = run({kExe, "merge", (dir / "c.exr").string(), (dir / "a.exr").string(), (dir / "b.exr").string(), "-o",
                           (dir / "merged.exr").string()},
                          dir / "merge.log");
  ASSERT_EQ(merged.status, 0) << merged.output;
  const Image m = read_exr(dir / "merged.exr"), single = read_exr(dir / "single.exr");
  expect_close_pixels(m, single);
  EXPECT_EQ(metadata_int(m, "spp"), 16);
  EXPECT_TRUE(std::filesystem::exists(dir / "merged.png"));
  ASSERT_NE(m.find_layer("S0"), nullptr) << "the spectral layer is merged too";

  // Checkpoints: exact double sums, so the floats match the single run (to the last bit, barring double rounding).
  const auto exact = run({kExe, "merge", (dir / "b.ckpt").string(), (dir / "c.ckpt").string(), (dir / "a.ckpt").string(), "-o",
                          (dir / "exact.exr").string()},
                         dir / "exact.log");
  ASSERT_EQ(exact.status, 0) << exact.output;
  EXPECT_NE(exact.output.find("exact"), std::string::npos) << exact.output;
  expect_close_pixels(read_exr(dir / "exact.exr"), single);

  // Refused: the same samples twice, a missing crop, another seed, mixed kinds.
  auto refused = [&](std::vector<std::string> files, const std::string& needle) {
    std::vector<std::string> args = {kExe, "merge"};
    for (const auto& f : files) args.push_back((dir / f).string());
    args.insert(args.end(), {"-o", (dir / "bad.exr").string()});
    const auto r = run(args, dir / "bad.log");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
  };
  refused({"a.exr", "a.exr", "b.exr", "c.exr"}, "overlaps");
  refused({"a.exr", "b.exr"}, "a part is missing");
  refused({"a.exr", "b.exr", "c.ckpt"}, "mixes checkpoints and EXR");
  const auto other = run(render_args(dir / "d.exr", {"--sample-range", "8:16"}, "9"), dir / "d.log");
  ASSERT_EQ(other.status, 0) << other.output;
  refused({"a.exr", "d.exr"}, "seed = 9: differs from");
}

}  // namespace
}  // namespace chlorovdb::test
