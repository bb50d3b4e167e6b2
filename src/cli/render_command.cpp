// `chlorovdb render`: load, render progressively, write EXR + PNG. Ctrl-C
// (or SIGTERM) stops after the current pass's tiles and still writes the
// completed passes, and a checkpoint when --checkpoint is given.
//
// Partial renders (docs/distributed.md): --crop renders a pixel window (the EXR
// has the crop's size; metadata gives its place), --sample-range A:B renders
// samples [A, B) of every pixel; `chlorovdb merge` reassembles them.
// Checkpoints: --checkpoint FILE [--checkpoint-every S] [--resume].
//
// Built a second time as `chlorovdb-mpi` (CHLOROVDB_MPI=ON, -DCHLOROVDB_MPI_MAIN):
// the ranks split the sample range and reduce the film sums to rank 0.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <unistd.h>

#include <fmt/format.h>

#ifdef CHLOROVDB_MPI_MAIN
#include <mpi.h>
#endif

#include "checkpoint/checkpoint.h"
#include "checkpoint/partition.h"
#include "cli/commands.h"
#include "core/error.h"
#include "cli/stopping_options.h"
#include "integrator/render.h"
#include "io/image.h"
#include "scene/scene_loader.h"

namespace chlorovdb::cli {

namespace {

std::atomic<bool> g_stop{false};

// This process's share of the work: rank r of `size` renders the r-th slice of the sample range.
struct Distribution {
  int rank = 0, size = 1;
};
Distribution g_dist;

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

struct RenderArgs {
  std::filesystem::path scene;
  std::filesystem::path output;  // .exr; the PNG preview goes beside it
  std::optional<int> spp, threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution;  // "WxH"
  std::optional<float> exposure;
  std::optional<std::string> fluorescence, transmittance;
  std::optional<std::string> crop, sample_range;  // "x0,y0,x1,y1", "A:B"
  std::filesystem::path checkpoint;
  double checkpoint_every = 300;
  bool resume = false;
  bool quiet = false;
  std::optional<double> target_error, time_limit;  // film/stopping_rule.h
  std::optional<std::string> target_region;        // "x0,y0,x1,y1"
};

int render(const RenderArgs& a);

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  RenderArgs& r = *args;
  CLI::App* sub = app.add_subcommand("render", "Render a scene to a linear EXR and a PNG preview");
  sub->add_option("scene", r.scene, "Scene file (JSON, docs/scene-format.md)")->required()->check(RegularFile);
  sub->add_option("-o,--output", r.output, "Output EXR (default: the scene's name in the current folder)");
  auto* spp = sub->add_option("--spp", r.spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24));
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  sub->add_option("--seed", r.seed, "Seed of the per-pixel random streams");
  sub->add_option("--resolution", r.resolution, "Image size WxH, e.g. 640x480");
  sub->add_option("--wavelengths", r.wavelengths, "Wavelengths per camera path")->check(CLI::Range(1, 16));
  sub->add_option("--exposure", r.exposure, "PNG preview exposure in stops");
  sub->add_option("--fluorescence", r.fluorescence, "auto | direct | full | reference | off");
  sub->add_option("--transmittance", r.transmittance, "auto | ratio | residual_ratio | delta");
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
      ->check(CLI::Range(0.0, 1e9))
      ->needs(ckpt);
  sub->add_flag("--resume", r.resume,
                "Continue from --checkpoint if it exists (start fresh if not); refused when the scene file, seed, size, "
                "crop or settings differ")
      ->needs(ckpt);
  sub->add_flag("-q,--quiet", r.quiet, "No progress bar");
  auto* target = sub->add_option("--target-error", r.target_error,
                                 "Stop once the relative standard error of the image (or --target-region) is at most this, "
                                 "looking at 16, 32, 64, ... spp (docs/convergence.md); --spp is then the maximum (default 65536)")
                     ->check(CLI::Range(1e-9, 1e9));
  sub->add_option("--target-region", r.target_region, "Pixels x0,y0,x1,y1 whose error --target-error measures")->needs(target);
  sub->add_option("--time-limit", r.time_limit, "Stop after the first pass that ends past this many seconds; writes what it has")
      ->check(CLI::Range(0.0, 1e9));
  return {sub, [args] { return render(*args); }};
}

namespace {

#ifdef CHLOROVDB_MPI_MAIN
// Sums `v` over the ranks into rank 0 (in chunks: MPI counts are int).
void reduce_sum(std::vector<double>& v) {
  std::vector<double> out(g_dist.rank == 0 ? v.size() : 0);
  constexpr size_t kChunk = size_t(1) << 26;
  for (size_t off = 0; off < v.size(); off += kChunk) {
    const int n = int(std::min(kChunk, v.size() - off));
    MPI_Reduce(v.data() + off, g_dist.rank == 0 ? out.data() + off : nullptr, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  }
  if (g_dist.rank == 0) v = std::move(out);
}
#endif

// The scene file's content and every setting that changes the image: parts
// and checkpoints must agree on all of them.
Signature make_signature(const RenderArgs& a, const Scene& scene) {
  const RenderSettings& s = scene.settings;
  return {
      {"scene_hash", hash_file(a.scene)},
      {"seed", std::to_string(s.seed)},
      {"wavelengths", std::to_string(s.wavelengths)},
      {"max_depth", std::to_string(s.max_depth)},
      {"fluorescence", to_string(s.fluorescence)},
      {"transmittance", s.transmittance_auto ? std::string("auto") : std::string(to_string(s.transmittance))},
      {"color_space", s.color_space == ColorSpace::sRGB ? "sRGB" : "ACEScg"},
      {"spectral_bins", std::to_string(s.spectral_bins)},
  };
}

// Refuses a checkpoint that another scene, seed, size, crop or range produced.
void check_resumable(const std::filesystem::path& file, const CheckpointHeader& h, const Film& saved, const PartInfo& now,
                     const SampleRange& range, const Film& film) {
  const std::string f = file.string();
  const char* hint = "refusing to resume: use the same scene file and options, or another --checkpoint file";
  if (h.full_width != now.full_width || h.full_height != now.full_height)
    throw InputError(f, "resolution", fmt::format("{}x{}", h.full_width, h.full_height),
                     fmt::format("the checkpoint's image size differs from this render's {}x{}: {}", now.full_width,
                                 now.full_height, hint));
  if (h.crop != now.crop)
    throw InputError(f, "crop", to_string(h.crop), fmt::format("differs from this render's --crop {}: {}", to_string(now.crop), hint));
  if (h.sample_first != range.begin)
    throw InputError(f, "sample_first", std::to_string(h.sample_first),
                     fmt::format("differs from this render's first sample {}: {}", range.begin, hint));
  if (const auto d = signature_difference(h.signature, now.signature))
    throw InputError(f, d->key, d->a,
                     fmt::format("the checkpoint was rendered with {} = {}, this render has {} = {}{}: {}", d->key, d->a,
                                 d->key, d->b, d->key == "scene_hash" ? " (the scene file changed)" : "", hint));
  if (saved.layer_names() != film.layer_names() || saved.spectral_bins() != film.spectral_bins() ||
      saved.color_space() != film.color_space())
    throw InputError(f, "layers", "", fmt::format("the checkpoint's film layers differ from this build's: {}", hint));
  if (h.samples_done > range.size())
    throw InputError(f, "samples_done", std::to_string(h.samples_done),
                     fmt::format("the checkpoint already holds more samples than this render's {}: {}", range.size(), hint));
}

int render(const RenderArgs& a) {
  const Distribution dist = g_dist;
  const bool root = dist.rank == 0;
  SceneOverrides o;
  o.spp = a.spp;
  if (a.target_error && !a.spp && !a.sample_range) o.spp = kTargetErrorMaxSpp;
  o.seed = a.seed;
  o.wavelengths = a.wavelengths;
  o.fluorescence = a.fluorescence;
  o.transmittance = a.transmittance;
  if (a.resolution) parse_resolution(*a.resolution, o);
  std::optional<SampleRange> requested;
  if (a.sample_range) requested = parse_sample_range(*a.sample_range);
  const Scene scene = load_scene(a.scene, o);
  const RenderSettings& s = scene.settings;
  const PixelWindow crop = a.crop ? parse_crop(*a.crop, s.width, s.height) : PixelWindow{0, 0, s.width, s.height};
  const SampleRange range = requested.value_or(SampleRange{0, s.spp});
  // This rank's slice of the range (the whole range without MPI).
  auto slice = [&](int r) {
    const int64_t n = range.size();
    return SampleRange{range.begin + int(n * r / dist.size), range.begin + int(n * (r + 1) / dist.size)};
  };
  const SampleRange mine = slice(dist.rank);
  const bool full_frame = crop == PixelWindow{0, 0, s.width, s.height};
  const StoppingRule stopping = make_stopping_rule(a.target_error, a.target_region, a.time_limit, crop, dist.size);
  StopDecision stopped;

  std::filesystem::path out = a.output.empty() ? std::filesystem::path(a.scene.stem().string() + ".exr") : a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (root && out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::filesystem::path png = out;
  png.replace_extension(".png");

  PartInfo part{s.width, s.height, crop, {}, make_signature(a, scene)};
  Film film(crop.width(), crop.height(), film_layer_names(), s.color_space);
  if (s.spectral_bins > 0) film.enable_spectral(kLambdaMin, kLambdaMax, s.spectral_bins);

  // Checkpoint: one file per rank under MPI.
  std::filesystem::path ckpt = a.checkpoint;
  if (!ckpt.empty() && dist.size > 1) ckpt += fmt::format(".rank{}of{}", dist.rank, dist.size);
  CheckpointHeader header{CHLOROVDB_VERSION, std::filesystem::absolute(a.scene).string(), s.width, s.height, crop,
                          mine.begin, mine.end, 0, part.signature, 0, 0};
  int resumed_at = 0;
  uint64_t nonfinite_before = 0;
  double seconds_before = 0;
  if (!ckpt.empty() && std::filesystem::exists(ckpt)) {
    if (!a.resume)
      throw InputError(ckpt.string(), "--checkpoint", "",
                       "exists: pass --resume to continue it, or remove it (or choose another file) to start over");
    CheckpointHeader saved;
    Film restored = read_checkpoint(ckpt, &saved);
    check_resumable(ckpt, saved, restored, part, mine, film);
    film = std::move(restored);
    resumed_at = saved.samples_done;
    nonfinite_before = saved.nonfinite_samples;
    seconds_before = saved.wall_time_s;
    if (saved.chlorovdb_version != CHLOROVDB_VERSION)
      fmt::print(stderr, "warning: {} was written by chlorovdb {}, this is {}: the result may differ from one run\n",
                 ckpt.string(), saved.chlorovdb_version, CHLOROVDB_VERSION);
    fmt::print(stderr, "{}resuming {} at sample {} of [{}, {})\n", dist.size > 1 ? fmt::format("rank {}: ", dist.rank) : "",
               ckpt.string(), mine.begin + resumed_at, mine.begin, mine.end);
  } else if (a.resume) {
    fmt::print(stderr, "{}no checkpoint {} yet: starting from the first sample\n",
               dist.size > 1 ? fmt::format("rank {}: ", dist.rank) : "", ckpt.string());
  }

  if (root && scene.has_fluorescence())
    fmt::print(stderr, "fluorescence: {} ({})\n", to_string(s.fluorescence), s.fluorescence_reason);

  const auto session_start = std::chrono::steady_clock::now();
  auto session_seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - session_start).count(); };
  int saved_done = resumed_at;
  auto save = [&](int done) {
    header.samples_done = done;
    header.nonfinite_samples = nonfinite_before + film.nonfinite_samples();
    header.wall_time_s = seconds_before + session_seconds();
    write_checkpoint(ckpt, header, film);
    saved_done = done;
  };
  auto last_save = std::chrono::steady_clock::now();

  g_stop = false;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  RenderOptions ro;
  ro.first_sample = mine.begin;
  ro.spp = mine.size();
  ro.samples_done = resumed_at;
  ro.film_x0 = crop.x0;
  ro.film_y0 = crop.y0;
  ro.threads = a.threads.value_or(0);
  ro.seed = s.seed;
  ro.stop = &g_stop;
  ro.show_progress = !a.quiet && root;
  if (!ckpt.empty())
    ro.on_pass = [&](int done) {
      const auto now = std::chrono::steady_clock::now();
      if (done < ro.spp && std::chrono::duration<double>(now - last_save).count() >= a.checkpoint_every) {
        save(done);
        last_save = now;
      }
    };
  ro.stop_after_pass = [&](const Film& f, int done) {
    stopped = check_stop(stopping, f, done, seconds_before + session_seconds());
    return stopped.reason != StopReason::none;
  };
  RenderStats stats;
  if (mine.size() > 0) stats = chlorovdb::render(scene, film, ro);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  // Final (or interrupted) state, so a completed part also leaves its exact sums.
  if (!ckpt.empty() && stats.samples_done > 0 && stats.samples_done != saved_done) save(stats.samples_done);

  int total_done = stats.samples_done;
  uint64_t nonfinite = nonfinite_before + film.nonfinite_samples();
  double seconds = seconds_before + session_seconds();
  bool interrupted = stats.interrupted;
  part.ranges = {SampleRange{mine.begin, mine.begin + stats.samples_done}};
  uint64_t paths = stats.paths.paths;
#ifdef CHLOROVDB_MPI_MAIN
  if (dist.size > 1) {
    for (size_t l = 0; l < film.layer_names().size(); ++l) {
      std::vector<double> v = film.raw_xyz(int(l));
      reduce_sum(v);
      if (root) set_raw_sums(film, int(l), v);
      std::vector<double> v2 = film.raw_rgb_squares(int(l));
      reduce_sum(v2);
      if (root) set_raw_rgb_squares(film, int(l), v2);
    }
    if (film.spectral_bins() > 0) {
      std::vector<double> v = film.raw_spectral();
      reduce_sum(v);
      if (root) set_raw_spectral(film, v);
    }
    std::vector<int> done(size_t(dist.size), 0);
    MPI_Gather(&stats.samples_done, 1, MPI_INT, done.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    const uint64_t mine_nonfinite = nonfinite, mine_paths = paths;
    MPI_Reduce(&mine_nonfinite, &nonfinite, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    MPI_Reduce(&mine_paths, &paths, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    const double mine_seconds = seconds;
    MPI_Reduce(&mine_seconds, &seconds, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    const int mine_interrupted = interrupted;
    int any_interrupted = 0;
    MPI_Reduce(&mine_interrupted, &any_interrupted, 1, MPI_INT, MPI_MAX, 0, MPI_COMM_WORLD);
    if (!root) return interrupted ? 130 : 0;
    interrupted = any_interrupted;
    part.ranges.clear();
    total_done = 0;
    for (int r = 0; r < dist.size; ++r) {
      part.ranges.push_back({slice(r).begin, slice(r).begin + done[size_t(r)]});
      total_done += done[size_t(r)];
    }
    part.ranges = normalized(part.ranges);
  }
#endif

  if (total_done == 0) {
    fmt::print(stderr, "interrupted before the first pass completed: nothing written\n");
    return 130;
  }
  Image image = film.to_image(total_done);
  image.metadata.set("spp", total_done);
  image.metadata.set("spp_requested", range.size());
  image.metadata.set("sample_first", range.begin);
  image.metadata.set("seed", std::to_string(s.seed));  // a string keeps all 64 bits
  image.metadata.set("wall_time_s", seconds);
  image.metadata.set("version", CHLOROVDB_VERSION);
  image.metadata.set("scene", std::filesystem::absolute(a.scene).string());
  image.metadata.set("wavelengths_per_path", s.wavelengths);
  image.metadata.set("fluorescence", to_string(s.fluorescence));
  {  // the majorant cell edge each grid medium chose (media/medium.cpp), for benchmarks
    std::string cells;
    for (const Medium& m : scene.media)
      if (!m.homogeneous()) cells += fmt::format("{}{}", cells.empty() ? "" : " ", m.majorant_grid().voxels_per_cell());
    if (!cells.empty()) image.metadata.set("majorant_cell_voxels", cells);
  }
  image.metadata.set("interrupted", interrupted ? 1 : 0);
  image.metadata.set("nonfinite_samples", double(nonfinite));  // including sessions before a resume
  if (resumed_at > 0) image.metadata.set("resumed_at_spp", resumed_at);
  set_stop_metadata(image.metadata, stopping, stopped, film, total_done);
  if (dist.size > 1) image.metadata.set("mpi_ranks", dist.size);
  set_part_metadata(image.metadata, part);
  write_exr(out, image);
  write_png(png, image.layers[0], crop.width(), crop.height(), a.exposure.value_or(s.exposure));

  const double mpaths = double(paths) / std::max(seconds - seconds_before, 1e-9) / 1e6;
  fmt::print(stderr, "{}: {} spp{}{} in {:.2f} s ({:.3f} M camera paths/s), wrote {} and {}{}\n",
             interrupted ? "interrupted" : "done", total_done,
             range == SampleRange{0, total_done} ? "" : fmt::format(" (samples {})", to_string(part.ranges)),
             full_frame ? "" : fmt::format(" of crop {}", to_string(crop)), seconds, mpaths, out.string(), png.string(),
             ckpt.empty() ? "" : fmt::format(" (checkpoint {})", dist.size > 1 ? a.checkpoint.string() + ".rank*" : ckpt.string()));
  if (stopped.reason != StopReason::none) fmt::print(stderr, "stopped early: {}\n", describe(stopped));
  if (nonfinite > 0) fmt::print(stderr, "warning: {} non-finite samples were dropped\n", nonfinite);
  return interrupted ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli

#ifdef CHLOROVDB_MPI_MAIN
// chlorovdb-mpi: `mpirun -np N chlorovdb-mpi render SCENE.json [render options]`.
int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &chlorovdb::cli::g_dist.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &chlorovdb::cli::g_dist.size);
  CLI::App app{"chlorovdb-mpi: `render` with the samples split over MPI ranks and the film reduced to rank 0"};
  app.set_version_flag("--version", std::string("chlorovdb-mpi ") + CHLOROVDB_VERSION);
  app.require_subcommand(1);
  const chlorovdb::cli::Command render = chlorovdb::cli::add_render_command(app);
  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    code = chlorovdb::cli::g_dist.rank == 0 ? app.exit(e) : e.get_exit_code();
    MPI_Finalize();
    return code;
  }
  try {
    code = render.run();
  } catch (const std::exception& e) {
    // Another rank may be waiting in a collective: take the whole job down.
    const bool input = dynamic_cast<const chlorovdb::InputError*>(&e) != nullptr;
    fmt::print(stderr, "chlorovdb-mpi (rank {}): {}: {}\n", chlorovdb::cli::g_dist.rank, input ? "error" : "internal error",
               e.what());
    MPI_Abort(MPI_COMM_WORLD, input ? 1 : 3);
  }
  MPI_Finalize();
  return code;
}
#endif
