// `chlorovdb reference`: a long, high-sample render that writes its EXR as it
// goes (metadata spp_done) and, with --resume, continues from where a previous
// run stopped: samples are deterministic per (pixel, sample index), so samples
// [spp_done, spp) are rendered and averaged with the stored mean, weighted by
// sample counts. The result equals an uninterrupted render up to float rounding.
#include <chrono>
#include <csignal>
#include <unistd.h>

#include <fmt/format.h>

#include "analysis/image_error.h"
#include "analysis/progressive.h"
#include "analysis/scene_variant.h"
#include "cli/commands.h"
#include "core/error.h"
#include "io/image.h"
#include "tracking/transmittance.h"

namespace chlorovdb::cli {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_reference_interrupt(int) {
  if (g_stop.exchange(true)) _exit(130);
}

struct ReferenceArgs {
  std::filesystem::path scene;
  std::filesystem::path output;
  int spp = 1024;
  double checkpoint_every = 60;
  bool resume = false;
  std::optional<int> threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution, fluorescence, transmittance;
  std::vector<std::string> sets;
  bool quiet = false;
};

// What must agree between a partial reference and the run that resumes it.
Metadata settings_metadata(const Scene& scene, const ReferenceArgs& a) {
  const RenderSettings& s = scene.settings;
  Metadata m;
  m.set("seed", std::to_string(s.seed));
  m.set("resolution", fmt::format("{}x{}", s.width, s.height));
  m.set("wavelengths_per_path", s.wavelengths);
  m.set("max_depth", s.max_depth);
  m.set("fluorescence", to_string(s.fluorescence));
  m.set("transmittance", s.transmittance_auto ? "auto" : to_string(s.transmittance));
  // Written only when given: EXR drops empty string attributes (a missing key reads as "").
  std::string sets;
  for (const std::string& x : a.sets) sets += (sets.empty() ? "" : " ") + x;
  if (!sets.empty()) m.set("scene_sets", sets);
  return m;
}

std::string value_text(const MetadataValue& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* i = std::get_if<int>(&v)) return std::to_string(*i);
  return fmt::format("{}", std::get<double>(v));
}

int reference(const ReferenceArgs& a);

}  // namespace

Command add_reference_command(CLI::App& app) {
  auto args = std::make_shared<ReferenceArgs>();
  ReferenceArgs& r = *args;
  CLI::App* sub = app.add_subcommand("reference", "Render a high-sample reference progressively, checkpointing; --resume continues it");
  sub->add_option("scene", r.scene, "Scene file")->required()->check(RegularFile);
  sub->add_option("-o,--output", r.output, "Output EXR (rewritten at every checkpoint)")->required();
  sub->add_option("--spp", r.spp, "Total samples per pixel")->check(CLI::Range(1, 1 << 24));
  sub->add_option("--checkpoint-every", r.checkpoint_every, "Seconds between checkpoint writes (0: after every pass)")
      ->check(CLI::Range(0.0, 1e9));
  sub->add_flag("--resume", r.resume, "Continue from the samples already in the output EXR (metadata spp_done)");
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  sub->add_option("--seed", r.seed, "Seed of the per-pixel random streams");
  sub->add_option("--resolution", r.resolution, "Image size WxH");
  sub->add_option("--wavelengths", r.wavelengths, "Wavelengths per camera path")->check(CLI::Range(1, 16));
  sub->add_option("--fluorescence", r.fluorescence, "auto | direct | full | reference | off");
  sub->add_option("--transmittance", r.transmittance, "auto | ratio | residual_ratio | delta");
  sub->add_option("--set", r.sets, "KEY=VALUE: change any scene key (repeatable)");
  sub->add_flag("-q,--quiet", r.quiet, "No progress bar");
  return {sub, [args] { return reference(*args); }};
}

namespace {

int reference(const ReferenceArgs& a) {
  SceneOverrides o;
  o.seed = a.seed;
  o.wavelengths = a.wavelengths;
  o.fluorescence = a.fluorescence;
  o.transmittance = a.transmittance;
  if (a.resolution) parse_resolution(*a.resolution, o);
  const Scene scene = load_scene_variant(a.scene, o, a.sets);
  std::filesystem::path out = a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const Metadata settings = settings_metadata(scene, a);
  if (!a.seed)
    fmt::print(stderr,
               "warning: no --seed: this reference uses the scene's seed {}, as renders of the scene do; a variant compared "
               "with it then shares its first samples and its error is underestimated (use e.g. --seed 1000003)\n",
               scene.settings.seed);

  // A previous partial run: check it is the same render, take its mean and count.
  std::optional<Image> previous;
  int previous_spp = 0;
  if (a.resume && std::filesystem::exists(out)) {
    previous = read_exr(out);
    const MetadataValue* done = previous->metadata.find("spp_done");
    if (!done || !std::holds_alternative<int>(*done))
      throw InputError(out.string(), "spp_done", "", "not a chlorovdb reference (no spp_done metadata): cannot resume");
    previous_spp = std::get<int>(*done);
    for (const char* key : {"seed", "resolution", "wavelengths_per_path", "max_depth", "fluorescence", "transmittance", "scene_sets"}) {
      const MetadataValue* was = previous->metadata.find(key);
      const MetadataValue* now = settings.find(key);
      const std::string a_text = was ? value_text(*was) : "", b_text = now ? value_text(*now) : "";
      if (a_text != b_text)
        throw InputError(out.string(), key, a_text.empty() ? "(none)" : a_text,
                         "differs from this run's " + (b_text.empty() ? "(none)" : b_text) + ": cannot resume a different render");
    }
    fmt::print(stderr, "resuming {} at {} of {} spp\n", out.string(), previous_spp, a.spp);
  } else if (a.resume) {
    fmt::print(stderr, "{} does not exist yet: starting from sample 0\n", out.string());
  }
  if (previous_spp >= a.spp) {
    fmt::print(stderr, "{} already holds {} spp (>= {}): nothing to do\n", out.string(), previous_spp, a.spp);
    return 0;
  }

  double seconds_before = 0;
  if (previous)
    if (const MetadataValue* t = previous->metadata.find("wall_time_s"); t && std::holds_alternative<double>(*t))
      seconds_before = std::get<double>(*t);
  const auto start = std::chrono::steady_clock::now();
  auto write = [&](const Image& mean, int spp_done) {
    Image image = mean;
    for (const auto& [key, value] : settings.entries) image.metadata.set(key, value);
    image.metadata.set("spp", spp_done);
    image.metadata.set("samples_per_pixel", double(spp_done));
    image.metadata.set("spp_done", spp_done);
    image.metadata.set("spp_target", a.spp);
    image.metadata.set("wall_time_s", seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    image.metadata.set("version", CHLOROVDB_VERSION);
    image.metadata.set("scene", std::filesystem::absolute(a.scene).string());
    write_exr(out, image);
    if (a.quiet) return;
    fmt::print(stderr, "\ncheckpoint: {} spp written to {}\n", spp_done, out.string());
  };

  ReferenceOptions ro;
  ro.spp = a.spp;
  ro.threads = a.threads.value_or(0);
  ro.seed = scene.settings.seed;
  ro.checkpoint_seconds = a.checkpoint_every;
  ro.stop = &g_stop;
  ro.show_progress = !a.quiet;
  g_stop = false;
  std::signal(SIGINT, on_reference_interrupt);
  std::signal(SIGTERM, on_reference_interrupt);
  const ReferenceResult r = continue_reference(scene, previous ? &*previous : nullptr, previous_spp, ro, write);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  fmt::print(stderr, "{}: {} of {} spp in {}, {:.1f} s this session\n", r.interrupted ? "interrupted" : "done",
             r.spp_done, a.spp, out.string(), r.seconds);
  for (const std::string layer : {"total", "fluorescence", "nonfluorescence"})
    if (const ReferenceSelfError e = reference_self_error(r.image, layer); e.available && e.mean != 0)
      fmt::print(stderr, "own error, layer {}: RMS standard error {:.3e} ({:.3g} % of its mean), adds {:.3e} to relMSE\n", layer,
                 e.rms_stderr, 100 * e.rms_stderr / std::abs(e.mean), e.rel_mse);
  return r.interrupted ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli
