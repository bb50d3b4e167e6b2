// `chlorovdb render`: load (with --set edits), run the render session
// (session/render_session.h), write EXR + PNG. Ctrl-C (or SIGTERM) stops after
// the current pass's tiles and still writes the completed passes, and a
// checkpoint when --checkpoint is given.
//
// Partial renders (docs/distributed.md): --crop renders a pixel window (the EXR
// has the crop's size; metadata gives its place), --sample-range A:B renders
// samples [A, B) of every pixel; `chlorovdb merge` reassembles them.
// Checkpoints: --checkpoint FILE [--checkpoint-every S] [--resume].
//
// Built a second time as `chlorovdb-mpi` (CHLOROVDB_MPI=ON, -DCHLOROVDB_MPI_MAIN):
// the ranks split the sample range and reduce the film sums to rank 0.
#include <chrono>
#include <cstdio>

#include <fmt/format.h>

#ifdef CHLOROVDB_MPI_MAIN
#include <mpi.h>
#endif

#include "checkpoint/partition.h"
#include "analysis/scene_variant.h"
#include "cli/commands.h"
#include "cli/scene_overrides.h"
#include "cli/stopping_options.h"
#include "core/error.h"
#include "integrator/continuation_guide_training.h"
#include "integrator/excitation_photons.h"
#include "io/image.h"
#include "scene/scene_loader.h"
#include "session/interrupt.h"
#include "session/render_session.h"

namespace chlorovdb::cli {

namespace {

// This process's share of the work (set by the MPI main).
RankGroup g_ranks;

struct RenderArgs {
  std::filesystem::path scene;
  std::filesystem::path output;  // .exr; the PNG preview goes beside it
  std::optional<int> spp, threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution;  // "WxH"
  std::optional<float> exposure;
  std::optional<std::string> fluorescence, transmittance, aovs;
  std::optional<std::string> crop, sample_range;  // "x0,y0,x1,y1", "A:B"
  std::vector<std::string> sets;                  // --set KEY=VALUE
  std::filesystem::path checkpoint;
  double checkpoint_every = 300;
  bool resume = false;
  bool quiet = false;
  std::optional<double> target_error, time_limit;  // film/stopping_rule.h
  std::optional<std::string> target_region;        // "x0,y0,x1,y1"
  bool adaptive = false;                           // film/adaptive.h
  int pilot_spp = 16;
};

int render(const RenderArgs& a);

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  RenderArgs& r = *args;
  CLI::App* sub = app.add_subcommand("render", "Render a scene to a linear EXR and a PNG preview");
  sub->add_option("scene", r.scene, "Scene file (JSON, docs/scene-format.md)")->required()->check(RegularFile);
  sub->add_option("-o,--output", r.output, "Output EXR (default: the scene's name in the current folder)");
  auto* spp = sub->add_option("--spp", r.spp, "Samples per pixel")->check(Integer(1, kMaxSpp));
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(Integer(1, kMaxThreads));
  add_scene_options(sub, r);
  sub->add_option("--exposure", r.exposure, "PNG preview exposure in stops")->check(Real(-40, 40));
  sub->add_option("--crop", r.crop,
                  "Render only pixels [x0, x1) x [y0, y1) as x0,y0,x1,y1; the EXR has the crop's size and its place in "
                  "metadata (`chlorovdb merge` reassembles crops)");
  sub->add_option("--sample-range", r.sample_range,
                  "Render samples [A, B) of every pixel as A:B (instead of --spp); parts with disjoint ranges merge "
                  "into one image")
      ->excludes(spp);
  auto* ckpt = sub->add_option("--checkpoint", r.checkpoint,
                               "Write the raw film sums (float64) to this file periodically, on Ctrl-C and at the end");
  sub->add_option("--checkpoint-every", r.checkpoint_every, "Seconds between checkpoints (0: after every pass; default 300)")
      ->check(Real(0, 1e9))
      ->needs(ckpt);
  sub->add_flag("--resume", r.resume,
                "Continue from --checkpoint if it exists (start fresh if not); refused when the scene file, seed, size, "
                "crop or settings differ")
      ->needs(ckpt);
  sub->add_flag("-q,--quiet", r.quiet, "No progress bar");
  auto* target = sub->add_option("--target-error", r.target_error,
                                 "Stop once the relative standard error of the image (or --target-region) is at most this, "
                                 "looking at 16, 32, 64, ... spp (docs/convergence.md); --spp is then the maximum (default 65536)")
                     ->check(Real(1e-9, 1e9));
  sub->add_option("--target-region", r.target_region, "Pixels x0,y0,x1,y1 whose error --target-error measures")->needs(target);
  auto* adaptive = sub->add_flag("--adaptive", r.adaptive,
                                 "With --target-error: samples per pixel from an independent pilot render, so that the "
                                 "image meets the target with fewer samples and stays unbiased (docs/convergence.md); "
                                 "writes an spp layer")
                       ->needs(target)
                       ->excludes(ckpt);
  sub->add_option("--pilot-spp", r.pilot_spp, "Samples per pixel of the --adaptive pilot (not in the image; default 16)")
      ->check(Integer(2, 4096))
      ->needs(adaptive);
  sub->add_option("--time-limit", r.time_limit, "Stop after the first pass that ends past this many seconds; writes what it has")
      ->check(Real(0, 1e9));
  return {sub, [args] { return render(*args); }};
}

namespace {

#ifdef CHLOROVDB_MPI_MAIN
// Sums `v` over the ranks into rank 0 (in chunks: MPI counts are int).
void reduce_sum(std::vector<double>& v) {
  const bool root = g_ranks.rank == 0;
  std::vector<double> out(root ? v.size() : 0);
  constexpr size_t kChunk = size_t(1) << 26;
  for (size_t off = 0; off < v.size(); off += kChunk) {
    const int n = int(std::min(kChunk, v.size() - off));
    MPI_Reduce(v.data() + off, root ? out.data() + off : nullptr, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  }
  if (root) v = std::move(out);
}
#endif

int render(const RenderArgs& a) {
  SceneOverrides o = scene_overrides(a);
  o.spp = a.spp;
  if (a.target_error && !a.spp && !a.sample_range) o.spp = kTargetErrorMaxSpp;
  RenderJob job;
  if (a.sample_range) job.samples = parse_sample_range(*a.sample_range);
  const Scene scene = load_scene(a.scene, o, a.sets);
  const RenderSettings& s = scene.settings;
  if (a.crop) job.crop = parse_crop(*a.crop, s.width, s.height);
  job.threads = a.threads.value_or(0);
  job.show_progress = !a.quiet;
  job.scene_hash = scene_hash(a.scene, a.sets);
  job.checkpoint = a.checkpoint;
  job.checkpoint_every = a.checkpoint_every;
  job.resume = a.resume;
  job.interrupt = &interrupt_requested();
  job.ranks = g_ranks;
  const bool root = job.ranks.rank == 0;
  if (root)
    for (const std::string& w : scene.warnings) fmt::print(stderr, "warning: {}\n", w);
  const PixelWindow crop = job.crop.value_or(PixelWindow{0, 0, s.width, s.height});
  const StoppingRule stopping = make_stopping_rule(a.target_error, a.target_region, a.time_limit, crop, job.ranks.size);
  if (a.adaptive)
    job.adaptive = AdaptiveSampling{.target_relative_error = *a.target_error, .region = stopping.region, .pilot_spp = a.pilot_spp,
                                    .min_spp = stopping.min_spp};
  // Adaptive: the counts meet the target, so passes stop only on the time limit (a
  // look at the image's own error would make the counts depend on its samples).
  StoppingRule pass_rule = stopping;
  if (a.adaptive) pass_rule.target_relative_error.reset();
  StopDecision stopped;
  const auto run_start = std::chrono::steady_clock::now();
  job.stop_after_pass = [&](const Film& f, int done) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
    stopped = check_stop(pass_rule, f, done, seconds);
    return stopped.reason != StopReason::none;
  };

  std::filesystem::path out = a.output.empty() ? std::filesystem::path(a.scene.stem().string() + ".exr") : a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (root && out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::filesystem::path png = out;
  png.replace_extension(".png");

  if (root && scene.has_fluorescence())
    fmt::print(stderr, "fluorescence: {} ({}){}{}\n", to_string(s.fluorescence), s.fluorescence_reason,
               uses_continuation_guides(scene) ? "; continuation directions guided" : "",
               uses_excitation_photons(scene)
                   ? fmt::format("; excitation from photons ({}; consistent, not unbiased)",
                                 describe_excitation_photons(s))
                   : "");
  RenderOutcome r = [&] {
    InterruptScope interrupts;
    return run_render_session(scene, job);
  }();
  if (!r.root()) return r.interrupted ? 130 : 0;
  if (r.samples_done == 0) {
    fmt::print(stderr, "interrupted before the first pass completed: nothing written\n");
    return 130;
  }
  Image image = session_image(scene, job, r);
  set_stop_metadata(image.metadata, stopping, stopped, r.film, r.samples_done);
  write_exr(out, image);
  write_png(png, image.layers[0], r.crop.width(), r.crop.height(), a.exposure.value_or(s.exposure));

  const bool full_frame = r.crop == PixelWindow{0, 0, s.width, s.height};
  const double mpaths = double(r.paths.paths) / std::max(r.session_seconds, 1e-9) / 1e6;
  fmt::print(stderr, "{}: {} spp{}{} in {:.2f} s ({:.3f} M camera paths/s), wrote {} and {}{}\n",
             r.interrupted ? "interrupted" : "done", r.samples_done,
             r.range == SampleRange{0, r.samples_done} ? "" : fmt::format(" (samples {})", to_string(r.part.ranges)),
             full_frame ? "" : fmt::format(" of crop {}", to_string(r.crop)), r.seconds, mpaths, out.string(), png.string(),
             a.checkpoint.empty() ? ""
                                  : fmt::format(" (checkpoint {})", r.ranks > 1 ? a.checkpoint.string() + ".rank*" : r.checkpoint.string()));
  if (stopped.reason != StopReason::none) fmt::print(stderr, "stopped early: {}\n", describe(stopped));
  if (scene.excitation_grids)
    fmt::print(stderr,
               "photon grid: {:.2g} % RMS relative standard error per cell (the photons' noise, the same at "
               "any spp; 4x render.excitation_photons halves it)\n",
               100.0 * excitation_grid_error(scene));
  if (const std::string routes = describe_excitation_routes(r.paths.excitation_routes); !routes.empty())
    fmt::print(stderr,
               "fluorescence seen, by what excited it (share of the mean / of the second moment per event, "
               "lanes' average): {}\n",
               routes);
  if (r.nonfinite_samples > 0) fmt::print(stderr, "warning: {} non-finite samples were dropped\n", r.nonfinite_samples);
  return r.interrupted ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli

#ifdef CHLOROVDB_MPI_MAIN
// chlorovdb-mpi: `mpirun -np N chlorovdb-mpi render SCENE.json [render options]`.
int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  chlorovdb::RankGroup& ranks = chlorovdb::cli::g_ranks;
  MPI_Comm_rank(MPI_COMM_WORLD, &ranks.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks.size);
  ranks.sum_to_root = chlorovdb::cli::reduce_sum;
  CLI::App app{"chlorovdb-mpi: `render` with the samples split over MPI ranks and the film reduced to rank 0"};
  app.set_version_flag("--version", std::string("chlorovdb-mpi ") + CHLOROVDB_VERSION);
  app.require_subcommand(1);
  const chlorovdb::cli::Command render = chlorovdb::cli::add_render_command(app);
  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    code = ranks.rank == 0 ? app.exit(e) : e.get_exit_code();
    MPI_Finalize();
    return code;
  }
  try {
    code = render.run();
  } catch (const std::exception& e) {
    // Another rank may be waiting in a collective: take the whole job down.
    const bool input = dynamic_cast<const chlorovdb::InputError*>(&e) != nullptr;
    fmt::print(stderr, "chlorovdb-mpi (rank {}): {}: {}\n", ranks.rank, input ? "error" : "internal error",
               e.what());
    MPI_Abort(MPI_COMM_WORLD, input ? 1 : 3);
  }
  MPI_Finalize();
  return code;
}
#endif
