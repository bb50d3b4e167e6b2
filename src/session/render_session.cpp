#include "session/render_session.h"

#include <algorithm>
#include <chrono>

#include <fmt/format.h>

#include "checkpoint/checkpoint.h"
#include "core/error.h"
#include "integrator/excitation_photons.h"
#include "media/medium.h"

namespace chlorovdb {

namespace {

ColorSpace job_color_space(const Scene& scene, const RenderJob& job) { return job.color_space.value_or(scene.settings.color_space); }
int job_bins(const Scene& scene, const RenderJob& job) { return job.spectral_bins.value_or(scene.settings.spectral_bins); }

// Every setting that changes the image: parts and checkpoints must agree on all of them.
Signature make_signature(const Scene& scene, const RenderJob& job) {
  const RenderSettings& s = scene.settings;
  Signature sig{
      {"scene_hash", job.scene_hash},
      {"seed", std::to_string(job_seed(scene, job))},
      {"wavelengths", std::to_string(s.wavelengths)},
      {"max_depth", std::to_string(s.max_depth)},
      {"fluorescence", to_string(s.fluorescence)},
      {"transmittance", s.transmittance_auto ? std::string("auto") : std::string(to_string(s.transmittance))},
      {"color_space", job_color_space(scene, job) == ColorSpace::sRGB ? "sRGB" : "ACEScg"},
      {"spectral_bins", std::to_string(job_bins(scene, job))},
  };
  // Only when asked for, so renders without AOVs keep matching older checkpoints and parts.
  if (s.aovs) sig.emplace_back("aovs", fmt::format("{}", fmt::join(aov_list(s.aovs), ",")));
  if (s.excitation_estimate == ExcitationEstimate::photons)
    sig.emplace_back("excitation_photons", describe_excitation_photons(s));
  return sig;
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
                                 d->key, d->b, d->key == "scene_hash" ? " (the scene file or its --set edits changed)" : "",
                                 hint));
  if (saved.layer_names() != film.layer_names() || saved.spectral_bins() != film.spectral_bins() ||
      saved.color_space() != film.color_space() || saved.aovs() != film.aovs())
    throw InputError(f, "layers", "", fmt::format("the checkpoint's film layers differ from this build's: {}", hint));
  if (h.samples_done > range.size())
    throw InputError(f, "samples_done", std::to_string(h.samples_done),
                     fmt::format("the checkpoint already holds more samples than this render's {}: {}", range.size(), hint));
}

// Rank 0 gets the sum of the film and the counters over the ranks.
void reduce_over_ranks(const RankGroup& g, const SampleRange& range, int done_here, RenderOutcome& o) {
  auto slice = [&](int r) {
    const int64_t n = range.size();
    return SampleRange{range.begin + int(n * r / g.size), range.begin + int(n * (r + 1) / g.size)};
  };
  for (size_t l = 0; l < o.film.layer_names().size(); ++l) {
    std::vector<double> v = o.film.raw_xyz(int(l));
    g.sum_to_root(v);
    if (g.rank == 0) set_raw_sums(o.film, int(l), v);
    std::vector<double> v2 = o.film.raw_rgb_squares(int(l));
    g.sum_to_root(v2);
    if (g.rank == 0) set_raw_rgb_squares(o.film, int(l), v2);
  }
  if (o.film.spectral_bins() > 0) {
    std::vector<double> v = o.film.raw_spectral();
    g.sum_to_root(v);
    if (g.rank == 0) set_raw_spectral(o.film, v);
  }
  if (o.film.aovs()) {
    std::vector<double> v = o.film.raw_aovs();
    g.sum_to_root(v);
    if (g.rank == 0) set_raw_aovs(o.film, v);
  }
  // One slot per rank for what is gathered or maximised, then the sums (exact in doubles below 2^53).
  const size_t n = size_t(g.size);
  const size_t routes = 3 * n + 5;  // then the excitation routes' sums, sums of squares and counts
  std::vector<double> v(routes + 3 * kExcitationRoutes + 1, 0.0);
  v[size_t(g.rank)] = done_here;
  v[n + size_t(g.rank)] = o.seconds;
  v[2 * n + size_t(g.rank)] = o.interrupted ? 1 : 0;
  v[3 * n] = double(o.nonfinite_samples);
  v[3 * n + 1] = double(o.paths.paths);
  v[3 * n + 2] = double(o.paths.fluorescence_events);
  v[3 * n + 3] = double(o.paths.excitation_rays);
  v[3 * n + 4] = double(o.paths.excitation_continuations);
  for (size_t r = 0; r < kExcitationRoutes; ++r) {
    v[routes + r] = o.paths.excitation_routes.sum[r];
    v[routes + kExcitationRoutes + r] = o.paths.excitation_routes.sum_squares[r];
    v[routes + 2 * kExcitationRoutes + r] = o.paths.excitation_routes.events[r];
  }
  v[routes + 3 * kExcitationRoutes] = o.paths.excitation_routes.events_any;
  g.sum_to_root(v);
  if (g.rank != 0) return;
  o.part.ranges.clear();
  o.samples_done = 0;
  o.seconds = 0;
  o.interrupted = false;
  for (int r = 0; r < g.size; ++r) {
    const int done = int(v[size_t(r)]);
    o.part.ranges.push_back({slice(r).begin, slice(r).begin + done});
    o.samples_done += done;
    o.seconds = std::max(o.seconds, v[n + size_t(r)]);
    o.interrupted = o.interrupted || v[2 * n + size_t(r)] > 0;
  }
  o.part.ranges = normalized(o.part.ranges);
  o.nonfinite_samples = uint64_t(v[3 * n]);
  o.paths = PathStats{};
  o.paths.paths = uint64_t(v[3 * n + 1]);
  o.paths.fluorescence_events = uint64_t(v[3 * n + 2]);
  o.paths.excitation_rays = uint64_t(v[3 * n + 3]);
  o.paths.excitation_continuations = uint64_t(v[3 * n + 4]);
  for (size_t r = 0; r < kExcitationRoutes; ++r) {
    o.paths.excitation_routes.sum[r] = v[routes + r];
    o.paths.excitation_routes.sum_squares[r] = v[routes + kExcitationRoutes + r];
    o.paths.excitation_routes.events[r] = v[routes + 2 * kExcitationRoutes + r];
  }
  o.paths.excitation_routes.events_any = v[routes + 3 * kExcitationRoutes];
}

}  // namespace

std::string scene_hash(const std::filesystem::path& file, std::span<const std::string> sets) {
  std::string h = hash_file(file);
  if (sets.empty()) return h;
  for (const std::string& set : sets) h += "\n" + set;
  return hash_text(h);
}

uint64_t job_seed(const Scene& scene, const RenderJob& job) { return job.seed.value_or(scene.settings.seed); }

RenderOutcome run_render_session(const Scene& scene, const RenderJob& job) {
  const RenderSettings& s = scene.settings;
  const RankGroup& g = job.ranks;
  if (g.size > 1 && !g.sum_to_root) throw std::invalid_argument("run_render_session: several ranks need sum_to_root");
  const PixelWindow crop = job.crop.value_or(PixelWindow{0, 0, s.width, s.height});
  const SampleRange range = job.samples.value_or(SampleRange{0, s.spp});
  const SampleRange mine{range.begin + int(int64_t(range.size()) * g.rank / g.size),
                         range.begin + int(int64_t(range.size()) * (g.rank + 1) / g.size)};
  const std::string who = g.size > 1 ? fmt::format("rank {}: ", g.rank) : "";

  RenderOutcome o{.film = Film(crop.width(), crop.height(), film_layer_names(), job_color_space(scene, job)),
                  .range = range,
                  .crop = crop,
                  .part = PartInfo{s.width, s.height, crop, {}, make_signature(scene, job)}};
  o.rank = g.rank;
  o.ranks = g.size;
  if (job_bins(scene, job) > 0) o.film.enable_spectral(kLambdaMin, kLambdaMax, job_bins(scene, job));
  o.film.enable_aovs(s.aovs);

  if (job.adaptive && (g.size > 1 || !job.checkpoint.empty()))
    throw InputError("command line", "--adaptive", "",
                     g.size > 1 ? "not available under MPI (the ranks would need the pilot's per-pixel counts); render without it"
                                : "not available with --checkpoint/--resume (a checkpoint does not carry the per-pixel counts)");
  o.checkpoint = job.checkpoint;
  if (!o.checkpoint.empty() && g.size > 1) o.checkpoint += fmt::format(".rank{}of{}", g.rank, g.size);
  CheckpointHeader header{CHLOROVDB_VERSION, std::filesystem::absolute(scene.file).string(), s.width, s.height, crop,
                          mine.begin, mine.end, 0, o.part.signature, 0, 0};
  uint64_t nonfinite_before = 0;
  double seconds_before = 0;
  if (!o.checkpoint.empty() && std::filesystem::exists(o.checkpoint)) {
    if (!job.resume)
      throw InputError(o.checkpoint.string(), "--checkpoint", "",
                       "exists: pass --resume to continue it, or remove it (or choose another file) to start over");
    CheckpointHeader saved;
    Film restored = read_checkpoint(o.checkpoint, &saved);
    check_resumable(o.checkpoint, saved, restored, o.part, mine, o.film);
    o.film = std::move(restored);
    o.resumed_at = saved.samples_done;
    nonfinite_before = saved.nonfinite_samples;
    seconds_before = saved.wall_time_s;
    if (saved.chlorovdb_version != CHLOROVDB_VERSION)
      fmt::print(stderr, "warning: {} was written by chlorovdb {}, this is {}: the result may differ from one run\n",
                 o.checkpoint.string(), saved.chlorovdb_version, CHLOROVDB_VERSION);
    fmt::print(stderr, "{}resuming {} at sample {} of [{}, {})\n", who, o.checkpoint.string(), mine.begin + o.resumed_at,
               mine.begin, mine.end);
  } else if (job.resume && !o.checkpoint.empty()) {
    fmt::print(stderr, "{}no checkpoint {} yet: starting from the first sample\n", who, o.checkpoint.string());
  }

  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  int saved_done = o.resumed_at;
  auto save = [&](int done) {
    header.samples_done = done;
    header.nonfinite_samples = nonfinite_before + o.film.nonfinite_samples();
    header.wall_time_s = seconds_before + elapsed();
    write_checkpoint(o.checkpoint, header, o.film);
    saved_done = done;
    if (job.on_checkpoint) job.on_checkpoint(o.film, done);
  };
  auto last_save = std::chrono::steady_clock::now();

  // The renderer sees one flag: the asynchronous interrupt, or this session's own.
  std::atomic<bool> own_stop{false};
  const std::atomic<bool>* stop = job.interrupt ? job.interrupt : &own_stop;
  bool polled = false;
  RenderOptions ro;
  ro.first_sample = mine.begin;
  ro.spp = mine.size();
  ro.samples_done = o.resumed_at;
  ro.film_x0 = crop.x0;
  ro.film_y0 = crop.y0;
  ro.threads = job.threads;
  ro.seed = job_seed(scene, job);
  ro.stop = stop;
  ro.show_progress = job.show_progress && g.rank == 0;
  ro.on_pass = [&](int done) {
    auto request_stop = [&] {
      // A const flag from the caller cannot be set: the session's own then stops the renderer.
      own_stop = true;
      ro.stop = &own_stop;
    };
    if (job.poll_interrupt && job.poll_interrupt()) {
      polled = true;
      request_stop();
    }
    if (done < ro.spp && job.stop_after_pass && job.stop_after_pass(o.film, done)) {
      o.stopped_by_rule = true;
      request_stop();
    }
    const auto now = std::chrono::steady_clock::now();
    if (!o.checkpoint.empty() && done < ro.spp && !own_stop &&
        std::chrono::duration<double>(now - last_save).count() >= job.checkpoint_every) {
      save(done);
      last_save = now;
    }
  };
  std::vector<int> pixel_spp;
  PathStats pilot_paths;
  if (job.adaptive && mine.size() > 0) {
    // The pilot: its own streams and film, so the counts are independent of the image's samples.
    AdaptiveSampling a = *job.adaptive;
    a.max_spp = mine.size();
    a.min_spp = std::min(a.min_spp, a.max_spp);
    Film pilot(o.film.width(), o.film.height(), film_layer_names(), o.film.color_space());
    RenderOptions po;
    po.spp = a.pilot_spp;
    po.film_x0 = crop.x0;
    po.film_y0 = crop.y0;
    po.threads = job.threads;
    po.seed = pilot_seed(ro.seed);
    po.stop = stop;
    pilot_paths = render(scene, pilot, po).paths;
    pixel_spp = adaptive_sample_counts(pilot, a);
    o.pilot_spp = a.pilot_spp;
    o.film.enable_sample_counts();
    ro.pixel_spp = &pixel_spp;
    ro.spp = *std::max_element(pixel_spp.begin(), pixel_spp.end());
  }
  RenderStats stats;
  if (mine.size() > 0) stats = render(scene, o.film, ro);
  stats.paths.paths += pilot_paths.paths;
  // The final (or stopped) state, so a completed part also leaves its exact sums.
  if (!o.checkpoint.empty() && stats.samples_done > 0 && stats.samples_done != saved_done) save(stats.samples_done);
  else if (job.on_checkpoint && o.checkpoint.empty() && stats.samples_done > 0) job.on_checkpoint(o.film, stats.samples_done);

  o.samples_done = stats.samples_done;
  o.session_seconds = elapsed();
  o.seconds = seconds_before + o.session_seconds;
  o.interrupted = (stats.interrupted && !o.stopped_by_rule) || polled;
  o.nonfinite_samples = nonfinite_before + o.film.nonfinite_samples();
  o.paths = stats.paths;
  o.part.ranges = {SampleRange{mine.begin, mine.begin + stats.samples_done}};
  if (g.size > 1) reduce_over_ranks(g, range, stats.samples_done, o);
  return o;
}

Image film_image(const Scene& scene, const RenderJob& job, const Film& film, int samples_done) {
  const RenderSettings& s = scene.settings;
  Image image = film.to_image(samples_done);
  Metadata& m = image.metadata;
  m.set("spp", samples_done);
  m.set("seed", std::to_string(job_seed(scene, job)));  // a string keeps all 64 bits
  m.set("version", CHLOROVDB_VERSION);
  m.set("scene", std::filesystem::absolute(scene.file).string());
  m.set("wavelengths_per_path", s.wavelengths);
  m.set("fluorescence", to_string(s.fluorescence));
  if (s.excitation_estimate == ExcitationEstimate::photons)
    m.set("excitation_photons", describe_excitation_photons(s));
  if (scene.excitation_grids) m.set("excitation_grid_error", fmt::format("{:.3g}", excitation_grid_error(scene)));
  {  // the majorant cell edge each grid medium chose (media/medium.cpp), for benchmarks
    std::string cells;
    for (const Medium& med : scene.media)
      if (!med.homogeneous()) cells += fmt::format("{}{}", cells.empty() ? "" : " ", med.majorant_grid().voxels_per_cell());
    if (!cells.empty()) m.set("majorant_cell_voxels", cells);
  }
  return image;
}

Image session_image(const Scene& scene, const RenderJob& job, const RenderOutcome& o) {
  Image image = film_image(scene, job, o.film, o.samples_done);
  Metadata& m = image.metadata;
  m.set("spp_requested", o.range.size());
  m.set("sample_first", o.range.begin);
  m.set("wall_time_s", o.seconds);
  m.set("interrupted", o.interrupted ? 1 : 0);
  if (o.stopped_by_rule) m.set("stopped_by_rule", 1);
  if (o.pilot_spp > 0) m.set("adaptive_pilot_spp", o.pilot_spp);
  m.set("nonfinite_samples", double(o.nonfinite_samples));  // including sessions before a resume
  if (o.resumed_at > 0) m.set("resumed_at_spp", o.resumed_at);
  if (o.ranks > 1) m.set("mpi_ranks", o.ranks);
  // What excited the fluorescence, over this session's samples (after a resume, the resumed part's).
  if (const std::string routes = describe_excitation_routes(o.paths.excitation_routes); !routes.empty())
    m.set("excitation_routes", routes);
  set_part_metadata(m, o.part);
  return image;
}

}  // namespace chlorovdb
