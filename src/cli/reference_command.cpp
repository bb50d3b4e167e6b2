// `chlorovdb reference`: a long, high-sample render that writes its EXR as it
// goes (metadata spp_done) and, with --resume, continues from where a previous
// run stopped. It is the render session (session/render_session.h) with its
// checkpoint at OUTPUT.ckpt: the exact film sums, so a resumed reference equals
// an uninterrupted one bit for bit.
#include <fmt/format.h>

#include "analysis/image_error.h"
#include "analysis/scene_variant.h"
#include "cli/commands.h"
#include "cli/scene_overrides.h"
#include "core/error.h"
#include "io/image.h"
#include "session/interrupt.h"
#include "session/render_session.h"

namespace chlorovdb::cli {

namespace {

struct ReferenceArgs {
  std::filesystem::path scene;
  std::filesystem::path output;
  int spp = 1024;
  double checkpoint_every = 60;
  bool resume = false;
  std::optional<int> threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution, fluorescence, transmittance, aovs;
  std::vector<std::string> sets;
  bool quiet = false;
};

int reference(const ReferenceArgs& a);

}  // namespace

Command add_reference_command(CLI::App& app) {
  auto args = std::make_shared<ReferenceArgs>();
  ReferenceArgs& r = *args;
  CLI::App* sub = app.add_subcommand("reference", "Render a high-sample reference progressively, checkpointing; --resume continues it");
  sub->add_option("scene", r.scene, "Scene file")->required()->check(RegularFile);
  sub->add_option("-o,--output", r.output, "Output EXR (rewritten at every checkpoint)")->required();
  sub->add_option("--spp", r.spp, "Total samples per pixel")->check(Integer(1, kMaxSpp));
  sub->add_option("--checkpoint-every", r.checkpoint_every, "Seconds between checkpoint writes (0: after every pass)")
      ->check(Real(0, 1e9));
  sub->add_flag("--resume", r.resume, "Continue from the checkpoint OUTPUT.ckpt (the exact film sums) the last run left");
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(Integer(1, kMaxThreads));
  add_scene_options(sub, r);
  sub->add_flag("-q,--quiet", r.quiet, "No progress bar");
  return {sub, [args] { return reference(*args); }};
}

namespace {

int reference(const ReferenceArgs& a) {
  const SceneOverrides o = scene_overrides(a);
  const Scene scene = load_scene(a.scene, o, a.sets);
  std::filesystem::path out = a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  if (!a.seed)
    fmt::print(stderr,
               "warning: no --seed: this reference uses the scene's seed {}, as renders of the scene do; a variant compared "
               "with it then shares its first samples and its error is underestimated (use e.g. --seed 1000003)\n",
               scene.settings.seed);

  RenderJob job;
  job.samples = SampleRange{0, a.spp};
  job.threads = a.threads.value_or(0);
  job.show_progress = !a.quiet;
  job.scene_hash = scene_hash(a.scene, a.sets);
  job.checkpoint = out.string() + ".ckpt";
  job.checkpoint_every = a.checkpoint_every;
  job.resume = a.resume;
  job.interrupt = &interrupt_requested();
  // Without --resume a reference starts over, as its EXR is overwritten.
  if (!a.resume) std::filesystem::remove(job.checkpoint);
  std::string sets;
  for (const std::string& x : a.sets) sets += (sets.empty() ? "" : " ") + x;
  // The reference's own keys, beside the session's (docs/convergence.md).
  auto write = [&](Image image, int spp_done) {
    image.metadata.set("resolution", fmt::format("{}x{}", scene.settings.width, scene.settings.height));
    image.metadata.set("max_depth", scene.settings.max_depth);
    image.metadata.set("transmittance", scene.settings.transmittance_auto ? "auto" : to_string(scene.settings.transmittance));
    // Written only when given: EXR drops empty string attributes.
    if (!sets.empty()) image.metadata.set("scene_sets", sets);
    image.metadata.set("samples_per_pixel", double(spp_done));
    image.metadata.set("spp_done", spp_done);
    image.metadata.set("spp_target", a.spp);
    write_exr(out, image);
  };
  job.on_checkpoint = [&](const Film& film, int spp_done) {
    write(film_image(scene, job, film, spp_done), spp_done);
    if (!a.quiet) fmt::print(stderr, "\ncheckpoint: {} spp written to {}\n", spp_done, out.string());
  };
  const RenderOutcome r = [&] {
    InterruptScope interrupts;
    return run_render_session(scene, job);
  }();
  const Image image = r.samples_done > 0 ? session_image(scene, job, r) : Image{};
  if (r.samples_done > 0) write(image, r.samples_done);
  fmt::print(stderr, "{}: {} of {} spp in {}, {:.1f} s this session\n", r.interrupted ? "interrupted" : "done",
             r.samples_done, a.spp, out.string(), r.session_seconds);
  if (r.samples_done == 0) return r.interrupted ? 130 : 0;
  for (const std::string layer : {"total", "fluorescence", "nonfluorescence"})
    if (const ReferenceSelfError e = reference_self_error(image, layer); e.available && e.mean != 0)
      fmt::print(stderr, "own error, layer {}: RMS standard error {:.3e} ({:.3g} % of its mean), adds {:.3e} to relMSE\n", layer,
                 e.rms_stderr, 100 * e.rms_stderr / std::abs(e.mean), e.rel_mse);
  return r.interrupted ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli
