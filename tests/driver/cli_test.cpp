// `chlorovdb render` / `merge` as a user runs them, in child processes: a render
// killed with SIGKILL resumes from its checkpoint to the same image as an
// uninterrupted run; Ctrl-C writes the image and a checkpoint; crops and sample
// ranges merge into the single-run image; bad combinations are refused;
// `reference` resumes bit for bit; `render --set` works in a read-only folder.
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
    for (float v : y)
      if (std::isfinite(v)) scale = std::max(scale, std::abs(v));
    for (size_t i = 0; i < x.size(); ++i)
      if (x[i] != y[i])  // equal, or both +inf (the depth of a pixel that saw no surface)
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

// A photon-grid render says how noisy its grid is, in the log and the image's
// metadata, and four times the photons halve it.
TEST(RenderCli, PhotonRenderReportsItsGridsError) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/default.json").string();
  const auto error_with = [&](const std::string& photons) {
    const auto r = run({kExe, "render", scene, "-o", (dir / "photons.exr").string(), "--resolution", "8x6", "--spp", "1",
                        "--threads", "1", "--set", "render.excitation_estimate=photons", "--set",
                        "render.excitation_photons=" + photons},
                       dir / "photons.log");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("photon grid: "), std::string::npos) << r.output;
    const Image img = read_exr(dir / "photons.exr");
    const MetadataValue* v = img.metadata.find("excitation_grid_error");
    EXPECT_NE(v, nullptr);
    return v && std::holds_alternative<std::string>(*v) ? std::stod(std::get<std::string>(*v)) : 0.0;
  };
  // Counts where the cells hold enough photons for the chunks' spread to measure
  // their noise (at 2^14 the spread still underestimates it).
  const double coarse = error_with("262144"), fine = error_with("1048576");
  EXPECT_GT(coarse, 0.0);
  EXPECT_NEAR(fine / coarse, 0.5, 0.05);
}

// What excited the fluorescence is reported by route, and only where something fluoresces.
TEST(RenderCli, RenderReportsWhatExcitedTheFluorescence) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/default.json").string();
  const auto log_with = [&](const std::string& fluorescence) {
    const auto r = run({kExe, "render", scene, "-o", (dir / "routes.exr").string(), "--resolution", "16x12", "--spp",
                        "4", "--threads", "1", "--fluorescence", fluorescence},
                       dir / "routes.log");
    EXPECT_EQ(r.status, 0) << r.output;
    return r.output;
  };
  const auto routes_metadata = [&] {
    const Image img = read_exr(dir / "routes.exr");
    const MetadataValue* v = img.metadata.find("excitation_routes");
    return v && std::holds_alternative<std::string>(*v) ? std::get<std::string>(*v) : std::string();
  };
  const std::string full = log_with("full");
  EXPECT_NE(full.find("fluorescence seen, by what excited it"), std::string::npos) << full;
  EXPECT_NE(full.find("connection to the lights"), std::string::npos) << full;
  EXPECT_NE(full.find(routes_metadata()), std::string::npos) << "the image's metadata holds the same line";
  EXPECT_NE(routes_metadata().find("connection to the lights"), std::string::npos);
  const std::string off = log_with("off");
  EXPECT_EQ(off.find("fluorescence seen, by what excited it"), std::string::npos) << off;
  EXPECT_EQ(routes_metadata(), "");
}

// The loader's doubts reach the user: the leaf's grid read in millimetres instead of
// its metres is a thousand times too small, and `render` says so.
TEST(RenderCli, PrintsTheScenesWarnings) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/leaf_D65.json").string();
  const auto r = run({kExe, "render", scene, "-o", (dir / "leaf.exr").string(), "--resolution", "4x3", "--spp", "1",
                      "--threads", "1", "--set", "media.leaf.pigments[0].grid.length_unit=mm", "--set",
                      "media.leaf.scattering.coefficient.length_unit=mm"},
                     dir / "leaf.log");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("warning: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check the grid's length unit"), std::string::npos) << r.output;
}

// A photon render of the leaf, whose pigment is a thin blade in its grid's box,
// warns that the photon cells cannot follow the light's fall across the blade.
TEST(RenderCli, WarnsWhenPhotonsMeetAPigmentHeldInAGrid) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/leaf_D65.json").string();
  const auto r = run({kExe, "render", scene, "-o", (dir / "leaf.exr").string(), "--resolution", "4x3", "--spp", "1",
                      "--threads", "1", "--set", "render.excitation_estimate=photons", "--set",
                      "render.excitation_photons=4096"},
                     dir / "leaf.log");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("holds its pigment in a grid"), std::string::npos) << r.output;
}

// Only the pigment's grid in millimetres: the leaf's two grids (the same file, read
// in two units) are then placed a thousand-fold apart, and one majorant grid over
// both cannot be built. The error names the medium and the key to check.
TEST(RenderCli, GridsOfOneMediumInDifferentLengthUnitsAreAnInputError) {
  const TestDir dir;
  const std::string scene = (std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/leaf_D65.json").string();
  const auto r = run({kExe, "render", scene, "-o", (dir / "leaf.exr").string(), "--resolution", "4x3", "--spp", "1",
                      "--threads", "1", "--set", "media.leaf.pigments[0].grid.length_unit=mm"},
                     dir / "leaf.log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("media.leaf"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("length_unit"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "leaf.exr"));
}

// `render --set` edits the scene in memory: a scene in a read-only folder renders,
// nothing is written beside it, its relative paths still resolve against its
// folder, and the edit changes the image (a stronger lamp, a brighter picture).
TEST(RenderCli, SetEditsASceneInAReadOnlyFolderWithoutWritingBesideIt) {
  const TestDir dir;
  const auto folder = dir / "readonly";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "floor.obj") << "v -40 0 -40\nv 40 0 -40\nv 40 0 40\nv -40 0 40\nf 1 4 3\nf 1 3 2\n";
  std::ofstream(folder / "scene.json") << R"({
    "length_unit": "cm",
    "render": {"resolution": [16, 12], "spp": 2, "wavelengths": 4},
    "camera": {"position": [0, 9, 26], "look_at": [0, 0, 0], "fov": 40},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "mesh", "file": "floor.obj", "material": "floor"},
               {"type": "quad", "corner": [-4, 10, -4], "edge_u": [8, 0, 0], "edge_v": [0, 0, 8],
                "emission": {"spectrum": "D65", "scale": 1}}]
  })";
  std::filesystem::permissions(folder, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec |
                                           std::filesystem::perms::group_read | std::filesystem::perms::others_read);
  auto listing = [&] {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(folder)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  };
  const std::vector<std::string> before = listing();
  auto render_to = [&](const std::string& name, std::vector<std::string> sets) {
    std::vector<std::string> a = {kExe, "render", (folder / "scene.json").string(), "-o", (dir / name).string(), "--threads", "1", "-q"};
    for (const std::string& s : sets) a.insert(a.end(), {"--set", s});
    const auto r = run(a, dir / (name + ".log"));
    EXPECT_EQ(r.status, 0) << r.output;
    return read_exr(dir / name);
  };
  const Image plain = render_to("plain.exr", {});
  const Image bright = render_to("bright.exr", {"shapes[1].emission.scale=4", "render.spp=2"});
  std::filesystem::permissions(folder, std::filesystem::perms::owner_all);
  EXPECT_EQ(listing(), before) << "nothing is written beside the scene";
  ASSERT_EQ(plain.layers[0].pixels.size(), bright.layers[0].pixels.size());
  double sum_plain = 0, sum_bright = 0;
  for (size_t i = 0; i < plain.layers[0].pixels.size(); ++i) {
    sum_plain += plain.layers[0].pixels[i];
    sum_bright += bright.layers[0].pixels[i];
  }
  ASSERT_GT(sum_plain, 0);
  // Same seed and samples, the one light four times as strong: four times the image.
  EXPECT_NEAR(sum_bright / sum_plain, 4.0, 1e-4);

  // A malformed edit is named.
  const auto bad = run({kExe, "render", (folder / "scene.json").string(), "-o", (dir / "bad.exr").string(), "--set", "shapes[9].x=1", "-q"},
                       dir / "bad.log");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("has no element 9"), std::string::npos) << bad.output;
}

// `reference` is the render session with its checkpoint beside the EXR: Ctrl-C
// writes the EXR so far, --resume continues from the exact sums, and the result
// is bit for bit the uninterrupted reference.
TEST(ReferenceCli, InterruptedReferenceResumesToTheUninterruptedOne) {
  const TestDir dir;
  auto args = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> a = {kExe, "reference", scene_file(), "-o", (dir / name).string(), "--spp", "400", "--resolution", "32x24",
                                  "--wavelengths", "4", "--seed", "3", "--threads", "2", "--checkpoint-every", "0", "-q",
                                  "--aovs", "alpha,depth,normal,albedo"};  // the compositing layers resume too
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  const Child c = spawn(args("int.exr", {}), dir / "int.log");
  ASSERT_TRUE(wait_for_file(c, dir / "int.exr.ckpt", std::chrono::seconds(60))) << read_text(dir / "int.log");
  ::kill(c.pid, SIGINT);
  EXPECT_EQ(wait_for(c), 130) << read_text(dir / "int.log");
  const Image partial = read_exr(dir / "int.exr");
  ASSERT_NE(partial.find_layer("albedo"), nullptr);
  const int done = metadata_int(partial, "spp_done");
  EXPECT_GT(done, 0);
  EXPECT_LT(done, 400);
  EXPECT_EQ(read_checkpoint_header(dir / "int.exr.ckpt").samples_done, done);

  const auto resumed = run(args("int.exr", {"--resume"}), dir / "resumed.log");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming"), std::string::npos) << resumed.output;
  const auto whole = run(args("whole.exr", {}), dir / "whole.log");
  ASSERT_EQ(whole.status, 0) << whole.output;
  const Image a = read_exr(dir / "int.exr");
  EXPECT_EQ(metadata_int(a, "spp_done"), 400);
  expect_same_pixels(a, read_exr(dir / "whole.exr"));

  // Another seed cannot resume it.
  auto other = args("int.exr", {"--resume"});
  other[std::find(other.begin(), other.end(), "--seed") - other.begin() + 1] = "4";
  const auto refused = run(other, dir / "refused.log");
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.output.find("seed"), std::string::npos) << refused.output;
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

// --adaptive: a pilot, then per-pixel counts within [16, --spp], written as an spp
// layer with adaptive = 1; refused with a checkpoint (the counts are not carried).
TEST(RenderCli, AdaptiveWritesPerPixelCounts) {
  const TestDir dir;
  auto r = run(render_args(dir / "a.exr", {"--target-error", "0.05", "--adaptive", "--pilot-spp", "8", "--spp", "40"}), dir / "a.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const Image img = read_exr(dir / "a.exr");
  EXPECT_EQ(metadata_int(img, "adaptive"), 1);
  EXPECT_EQ(metadata_int(img, "adaptive_pilot_spp"), 8);
  const ImageLayer* spp = img.find_layer("spp");
  ASSERT_NE(spp, nullptr);
  float lo = 1e9f, hi = 0;
  for (float n : spp->pixels) lo = std::min(lo, n), hi = std::max(hi, n);
  EXPECT_GE(lo, 16.f);
  EXPECT_LE(hi, 40.f);
  EXPECT_EQ(metadata_int(img, "spp"), int(hi));
  r = run({kExe, "merge", (dir / "a.exr").string(), "-o", (dir / "m.exr").string()}, dir / "m.log");  // counts per pixel
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("adaptive"), std::string::npos) << r.output;
  r = run(render_args(dir / "c.exr", {"--target-error", "0.05", "--adaptive", "--checkpoint", (dir / "c.ckpt").string()}), dir / "c.log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("--adaptive"), std::string::npos) << r.output;
  r = run(render_args(dir / "d.exr", {"--adaptive"}), dir / "d.log");
  EXPECT_NE(r.status, 0) << r.output;
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

TEST(MeasureCli, ReportsEverySensorByNameWithoutARegion) {
  const TestDir dir;
  std::string json = read_text(scene_file());
  json.insert(json.rfind('}'), R"(, "sensors": {"left": {"region": [0, 0, 4, 4]}, "centre": {"region": [14, 10, 18, 14]}})");
  std::ofstream(dir / "sensors.json") << json;
  const std::vector<std::string> base = {kExe, "measure", (dir / "sensors.json").string(), "--resolution", "32x24", "--spp", "4",
                                         "--batches", "2", "--bands", "2", "--threads", "2"};
  auto args = base;
  args.insert(args.end(), {"--csv", (dir / "s.csv").string()});
  auto r = run(args, dir / "s.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("sensor \"left\": region 0,0,4,4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sensor \"centre\": region 14,10,18,14"), std::string::npos) << r.output;
  const std::string csv = read_text(dir / "s.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 2 * (1 + 3 * 6 + 2)) << csv;
  EXPECT_NE(csv.find("\"14,10,18,14\",centre\n"), std::string::npos) << csv;
  // --region overrides the sensors; a sensor outside a smaller --resolution is refused by name.
  args = base;
  args.insert(args.end(), {"--region", "1,1,2,2"});
  r = run(args, dir / "r.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("sensor \""), std::string::npos) << r.output;
  args = base;
  args[4] = "16x12";
  r = run(args, dir / "small.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("sensors.centre.region"), std::string::npos) << r.output;
  // No sensors and no --region: told what to give.
  r = run({kExe, "measure", scene_file(), "--resolution", "8x8", "--spp", "2", "--batches", "2"}, dir / "none.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("--region"), std::string::npos) << r.output;
}

TEST(AovCli, LayersSurviveResumeAndMerge) {
  const TestDir dir;
  const std::vector<std::string> aovs = {"--aovs", "alpha,depth,normal,albedo"};
  auto with = [&](std::vector<std::string> extra) {
    extra.insert(extra.end(), aovs.begin(), aovs.end());
    return extra;
  };
  auto r = run(render_args(dir / "single.exr", with({"--spp", "16"})), dir / "single.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const Image single = read_exr(dir / "single.exr");
  for (const char* name : {"alpha", "depth", "N", "albedo"}) ASSERT_NE(single.find_layer(name), nullptr) << name;
  EXPECT_EQ(metadata_text(single, "aovs"), "alpha,depth,normal,albedo");
  // Resume: 8 samples into a checkpoint, then on to 16, is the single run bit for bit.
  const auto ckpt = dir / "resume.ckpt";
  r = run(render_args(dir / "resumed.exr", with({"--spp", "8", "--checkpoint", ckpt.string()})), dir / "first.log");
  ASSERT_EQ(r.status, 0) << r.output;
  r = run(render_args(dir / "resumed.exr", {"--spp", "16", "--checkpoint", ckpt.string(), "--resume"}), dir / "other.log");
  EXPECT_EQ(r.status, 1) << "resumed without the checkpoint's AOVs: " << r.output;
  EXPECT_NE(r.output.find("aovs"), std::string::npos) << r.output;
  r = run(render_args(dir / "resumed.exr", with({"--spp", "16", "--checkpoint", ckpt.string(), "--resume"})), dir / "resume.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_pixels(read_exr(dir / "resumed.exr"), single);
  // Merge two sample ranges, as checkpoints (exact sums) and as EXRs (float means; Z weighted by coverage).
  for (const auto& [name, range] : {std::pair{"a", "0:8"}, std::pair{"b", "8:16"}}) {
    r = run(render_args(dir / (std::string(name) + ".exr"),
                        with({"--sample-range", range, "--checkpoint", (dir / (std::string(name) + ".ckpt")).string()})),
            dir / (std::string(name) + ".log"));
    ASSERT_EQ(r.status, 0) << r.output;
  }
  r = run({kExe, "merge", (dir / "a.ckpt").string(), (dir / "b.ckpt").string(), "-o", (dir / "m_ckpt.exr").string()}, dir / "mc.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_close_pixels(read_exr(dir / "m_ckpt.exr"), single);
  r = run({kExe, "merge", (dir / "a.exr").string(), (dir / "b.exr").string(), "-o", (dir / "m_exr.exr").string()}, dir / "me.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_close_pixels(read_exr(dir / "m_exr.exr"), single);
  // A misspelt AOV is refused by name.
  r = run(render_args(dir / "bad.exr", {"--aovs", "alpha,dpeth"}), dir / "bad.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("--aovs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("did you mean \"depth\""), std::string::npos) << r.output;
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

// Every numeric option of every subcommand refuses words that do not fit its
// type or range (CLI11 alone wrapped "-1" into a uint64 and let NaN through
// Range), naming the option; nothing is rendered or written.
TEST(NumericOptionsCli, OutOfRangeAndNonFiniteWordsAreRefused) {
  const TestDir dir;
  const std::string scene = scene_file(), out = (dir / "o.exr").string();
  const std::vector<std::vector<std::string>> bad = {
      {"render", scene, "-o", out, "--resolution", "4294967312x12"},
      {"render", scene, "-o", out, "--resolution", "0x12"},
      {"render", scene, "-o", out, "--resolution", "65537x12"},
      {"render", scene, "-o", out, "--resolution", "12x12x"},
      {"render", scene, "-o", out, "--seed", "-1"},
      {"render", scene, "-o", out, "--seed", "18446744073709551616"},
      {"render", scene, "-o", out, "--seed", "3.5"},
      {"render", scene, "-o", out, "--exposure", "nan"},
      {"render", scene, "-o", out, "--exposure", "inf"},
      {"render", scene, "-o", out, "--exposure", "1e400"},
      {"render", scene, "-o", out, "--exposure", "41"},
      {"render", scene, "-o", out, "--checkpoint", (dir / "c.ckpt").string(), "--checkpoint-every", "nan"},
      {"render", scene, "-o", out, "--checkpoint", (dir / "c.ckpt").string(), "--checkpoint-every", "-1"},
      {"render", scene, "-o", out, "--spp", "4294967297"},
      {"render", scene, "-o", out, "--spp", "0"},
      {"render", scene, "-o", out, "--threads", "1e3"},
      {"render", scene, "-o", out, "--wavelengths", "17"},
      {"reference", scene, "-o", out, "--seed", "-1"},
      {"reference", scene, "-o", out, "--checkpoint-every", "inf"},
      {"reference", scene, "-o", out, "--resolution", "4294967312x12"},
      {"converge", scene, "--reference", scene, "-o", (dir / "c").string(), "--seed", "18446744073709551616"},
      {"converge", scene, "--reference", scene, "-o", (dir / "c").string(), "--threads", "0"},
      {"export-pbrt", scene, "-o", (dir / "s.pbrt").string(), "--max-grid-voxels", "-5"},
      {"export-pbrt", scene, "-o", (dir / "s.pbrt").string(), "--resolution", "-3x4"},
      {"merge", scene, "-o", out, "--exposure", "nan"},
      {"voxelize", scene, "-o", (dir / "v.vdb").string(), "--voxel-size", "0.1", "--concentration", "inf"},
      {"voxelize", scene, "-o", (dir / "v.vdb").string(), "--voxel-size", "0.1", "--noise-seed", "-1"},
      {"voxelize", scene, "-o", (dir / "v.vdb").string(), "--voxel-size", "0.1", "--scale", "1e39"},
  };
  for (const auto& args : bad) {
    std::vector<std::string> full = {kExe};
    full.insert(full.end(), args.begin(), args.end());
    std::string line;
    for (const auto& a : args) line += a + " ";
    const auto r = run(full, dir / "bad.log");
    EXPECT_TRUE(r.status == 1 || r.status == 105 || r.status == 106) << line << "-> " << r.status << "\n" << r.output;
    // The message names the offending word (or option).
    EXPECT_NE(r.output.find(args.back()), std::string::npos) << line << "\n" << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  // The largest seed is a seed.
  const auto ok = run(render_args(dir / "max_seed.exr", {"--spp", "1"}, "18446744073709551615"), dir / "ok.log");
  EXPECT_EQ(ok.status, 0) << ok.output;
}

// Two renders writing the same output at once never leave a torn file: each
// writes a temporary of its own beside it and renames it into place.
TEST(AtomicOutputCli, ConcurrentRendersToOnePathLeaveAWholeImage) {
  const TestDir dir;
  const auto out = dir / "same.exr";
  std::vector<Child> children;
  for (int i = 0; i < 3; ++i)
    children.push_back(spawn(render_args(out, {"--spp", "2"}), dir / ("w" + std::to_string(i) + ".log")));
  for (const Child& c : children) EXPECT_EQ(wait_for(c), 0);
  const auto single = run(render_args(dir / "single.exr", {"--spp", "2"}), dir / "single.log");
  ASSERT_EQ(single.status, 0) << single.output;
  expect_same_pixels(read_exr(out), read_exr(dir / "single.exr"));
  for (const auto& e : std::filesystem::directory_iterator(dir / "."))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
}

// `chlorovdb info` on a cut .vdb refuses it, naming the file, where it used to
// build strings of garbage length until it was killed.
TEST(InfoCli, TruncatedVdbIsRefused) {
  const TestDir dir;
  const auto whole = std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "volumes/spill_1uM.vdb";
  const std::string bytes = read_text(whole);
  for (const size_t keep : {size_t(100), size_t(600), bytes.size() / 2}) {
    const auto cut = dir / "cut.vdb";
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, keep);
    const auto r = run({kExe, "info", cut.string()}, dir / "info.log");
    EXPECT_EQ(r.status, 1) << keep << "\n" << r.output;
    EXPECT_NE(r.output.find("cut.vdb"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace chlorovdb::test
