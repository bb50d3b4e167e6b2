// `chlorovdb render`: load, render progressively, write EXR + PNG. Ctrl-C
// stops after the current pass's tiles and still writes the completed passes.
#include <csignal>
#include <cstdio>
#include <unistd.h>

#include <fmt/format.h>

#include "cli/commands.h"
#include "core/error.h"
#include "integrator/render.h"
#include "io/image.h"
#include "scene/scene_loader.h"

namespace chlorovdb::cli {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_interrupt(int) {
  // A second Ctrl-C means "now": leave without writing.
  if (g_stop.exchange(true)) _exit(130);
}

void parse_resolution(const std::string& s, SceneOverrides& o) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 65536 || h > 65536)
    throw InputError("command line", "--resolution", s, "expected WxH with 1 <= W, H <= 65536, e.g. 640x480");
  o.width = w;
  o.height = h;
}

const char* mode_name(FluorescenceMode m) {
  switch (m) {
    case FluorescenceMode::off: return "off";
    case FluorescenceMode::direct: return "direct";
    case FluorescenceMode::full: return "full";
    case FluorescenceMode::reference: return "reference";
  }
  return "?";
}

struct RenderArgs {
  std::filesystem::path scene;
  std::filesystem::path output;  // .exr; the PNG preview goes beside it
  std::optional<int> spp, threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution;  // "WxH"
  std::optional<float> exposure;
  std::optional<std::string> fluorescence, transmittance;
  bool quiet = false;
};

int render(const RenderArgs& a);

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  RenderArgs& r = *args;
  CLI::App* sub = app.add_subcommand("render", "Render a scene to a linear EXR and a PNG preview");
  sub->add_option("scene", r.scene, "Scene file (JSON, docs/scene-format.md)")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", r.output, "Output EXR (default: the scene's name in the current folder)");
  sub->add_option("--spp", r.spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24));
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  sub->add_option("--seed", r.seed, "Seed of the per-pixel random streams");
  sub->add_option("--resolution", r.resolution, "Image size WxH, e.g. 640x480");
  sub->add_option("--wavelengths", r.wavelengths, "Wavelengths per camera path")->check(CLI::Range(1, 16));
  sub->add_option("--exposure", r.exposure, "PNG preview exposure in stops");
  sub->add_option("--fluorescence", r.fluorescence, "auto | direct | full | reference | off");
  sub->add_option("--transmittance", r.transmittance, "auto | ratio | residual_ratio | delta");
  sub->add_flag("-q,--quiet", r.quiet, "No progress bar");
  return {sub, [args] { return render(*args); }};
}

namespace {

int render(const RenderArgs& a) {
  SceneOverrides o;
  o.spp = a.spp;
  o.seed = a.seed;
  o.wavelengths = a.wavelengths;
  o.fluorescence = a.fluorescence;
  o.transmittance = a.transmittance;
  if (a.resolution) parse_resolution(*a.resolution, o);
  const Scene scene = load_scene(a.scene, o);
  const RenderSettings& s = scene.settings;

  std::filesystem::path out = a.output.empty() ? std::filesystem::path(a.scene.stem().string() + ".exr") : a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::filesystem::path png = out;
  png.replace_extension(".png");

  if (scene.has_fluorescence())
    fmt::print(stderr, "fluorescence: {} ({})\n", mode_name(s.fluorescence), s.fluorescence_reason);
  Film film(s.width, s.height, film_layer_names(), s.color_space);
  if (s.spectral_bins > 0) film.enable_spectral(kLambdaMin, kLambdaMax, s.spectral_bins);

  g_stop = false;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  RenderOptions ro;
  ro.spp = s.spp;
  ro.threads = a.threads.value_or(0);
  ro.seed = s.seed;
  ro.stop = &g_stop;
  ro.show_progress = !a.quiet;
  const RenderStats stats = chlorovdb::render(scene, film, ro);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);

  if (stats.samples_done == 0) {
    fmt::print(stderr, "interrupted before the first pass completed: nothing written\n");
    return 130;
  }
  Image image = film.to_image(stats.samples_done);
  image.metadata.set("spp", stats.samples_done);
  image.metadata.set("spp_requested", s.spp);
  image.metadata.set("seed", std::to_string(s.seed));  // a string keeps all 64 bits
  image.metadata.set("wall_time_s", stats.seconds);
  image.metadata.set("version", CHLOROVDB_VERSION);
  image.metadata.set("scene", std::filesystem::absolute(a.scene).string());
  image.metadata.set("wavelengths_per_path", s.wavelengths);
  image.metadata.set("fluorescence", mode_name(s.fluorescence));
  image.metadata.set("interrupted", stats.interrupted ? 1 : 0);
  write_exr(out, image);
  write_png(png, image.layers[0], s.width, s.height, a.exposure.value_or(s.exposure));

  const double mpaths = stats.paths.paths / std::max(stats.seconds, 1e-9) / 1e6;
  fmt::print(stderr, "{}: {} spp in {:.2f} s ({:.3f} M camera paths/s), wrote {} and {}\n",
             stats.interrupted ? "interrupted" : "done", stats.samples_done, stats.seconds, mpaths, out.string(),
             png.string());
  if (film.nonfinite_samples() > 0)
    fmt::print(stderr, "warning: {} non-finite samples were dropped\n", film.nonfinite_samples());
  return stats.interrupted ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli
