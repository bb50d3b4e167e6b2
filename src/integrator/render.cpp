#include "integrator/render.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <fmt/format.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "integrator/aov.h"
#include "integrator/continuation_guide_training.h"
#include "integrator/excitation_photons.h"
#include "io/progress.h"

namespace chlorovdb {

namespace {

constexpr int kTileSize = 16;

struct Tile {
  int x0, y0, x1, y1;
};

// Tiles over image pixels [x0, x1) x [y0, y1).
std::vector<Tile> make_tiles(int x0, int y0, int x1, int y1) {
  std::vector<Tile> tiles;
  for (int y = y0; y < y1; y += kTileSize)
    for (int x = x0; x < x1; x += kTileSize)
      tiles.push_back({x, y, std::min(x + kTileSize, x1), std::min(y + kTileSize, y1)});
  return tiles;
}

// `film` holds image pixels from (fx0, fy0) on.
// With `pixel_spp`, pixel p renders samples up to first_sample + pixel_spp[p] and counts them.
void render_tile(const Scene& scene, Film& film, int fx0, int fy0, const Tile& tile, int s0, int s1, uint64_t seed,
                 int first_sample, const std::vector<int>* pixel_spp, PathStats& stats) {
  const int n_lambda = scene.settings.wavelengths;
  const AovMask aovs = film.aovs();
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int x = tile.x0; x < tile.x1; ++x) {
      int end = s1;
      if (pixel_spp) {
        end = std::min(s1, first_sample + (*pixel_spp)[size_t(y - fy0) * size_t(film.width()) + size_t(x - fx0)]);
        if (end > s0) film.add_sample_count(x - fx0, y - fy0, end - s0);
      }
      for (int s = s0; s < end; ++s) {
        Rng rng = sample_rng(seed, x, y, s);
        SampledWavelengths lambda = scene.camera_wavelengths.sample(rng.uniform(), n_lambda);
        const Point2 film_pos{x + rng.uniform(), y + rng.uniform()};  // box filter
        const Ray ray = scene.camera.generate_ray(film_pos, Point2{rng.uniform(), rng.uniform()});
        const PathRadiance L = trace_path(scene, ray, scene.camera_medium, lambda, rng, stats);
        const SampledSpectrum layers[] = {L.fluorescence + L.other, L.fluorescence, L.other};
        static_assert(kLayerTotal == 0 && kLayerFluorescence == 1 && kLayerNonFluorescence == 2);
        if (!aovs) {
          film.add_sample(x - fx0, y - fy0, layers, lambda);
          continue;
        }
        // The same camera ray and wavelengths; a stream of its own, so the image is the same with or without AOVs.
        Rng aov_rng = sample_rng(~seed, x, y, s);
        const AovSample aov = trace_aovs(scene, ray, scene.camera_medium, lambda, aov_rng, aovs);
        film.add_sample(x - fx0, y - fy0, layers, lambda, &aov);
      }
    }
}

}  // namespace

// Passes grow 1, 1, 2, 4, 8, 8, ...: the first image appears fast, and an
// interrupt loses at most one short pass. A function of `done` only (and of the
// total at the very end), so a resumed render repeats the same passes.
int pass_size(int done, int total) { return std::min(total - done, std::clamp(done, 1, 8)); }

std::vector<std::string> film_layer_names() { return {"total", "fluorescence", "nonfluorescence"}; }

Rng sample_rng(uint64_t seed, int x, int y, int sample) {
  const uint64_t pixel = (uint64_t(uint32_t(y)) << 32) | uint32_t(x);
  return Rng(hash_combine(hash_combine(seed, pixel), uint64_t(sample)), mix_bits(seed + 1));
}

RenderStats render(const Scene& scene, Film& film, const RenderOptions& options) {
  RenderStats result;
  const auto start = std::chrono::steady_clock::now();
  const int width = scene.settings.width, height = scene.settings.height;
  const int fx0 = options.film_x0, fy0 = options.film_y0;
  if (fx0 < 0 || fy0 < 0 || fx0 + film.width() > width || fy0 + film.height() > height)
    throw std::invalid_argument(fmt::format("render: a {}x{} film at ({}, {}) does not fit the {}x{} image", film.width(),
                                            film.height(), fx0, fy0, width, height));
  if (options.samples_done < 0 || options.samples_done > options.spp || options.first_sample < 0)
    throw std::invalid_argument(fmt::format("render: samples_done {} outside [0, spp = {}] or first_sample {} < 0",
                                            options.samples_done, options.spp, options.first_sample));
  if (options.pixel_spp &&
      (!film.has_sample_counts() || options.pixel_spp->size() != size_t(film.width()) * size_t(film.height())))
    throw std::invalid_argument("render: pixel_spp needs a film that counts samples and one count per film pixel");
  const std::vector<Tile> tiles = make_tiles(fx0, fy0, fx0 + film.width(), fy0 + film.height());
  tbb::enumerable_thread_specific<PathStats> stats;
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  std::unique_ptr<Progress> progress;
  if (options.show_progress) progress = std::make_unique<Progress>(int64_t(tiles.size()) * (options.spp - options.samples_done), "render");

  // Learned from the scene before the first pass, once per scene; its time is part of the render's.
  arena.execute([&] {
    prepare_continuation_guides(scene);
    prepare_excitation_grids(scene, options.seed, options.stop);
  });

  auto stopped = [&] { return options.stop && options.stop->load(std::memory_order_relaxed); };
  int done = options.samples_done;
  while (done < options.spp && !stopped()) {
    const int count = pass_size(done, options.spp);
    const int s0 = options.first_sample + done;
    // Each pass renders into its own film, merged only when complete, so an
    // interrupted pass never leaves pixels with fewer samples than the others.
    Film pass = film.empty_like();
    std::atomic<bool> pass_complete{true};
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t < r.end(); ++t) {
          if (stopped()) {
            pass_complete = false;
            return;
          }
          render_tile(scene, pass, fx0, fy0, tiles[t], s0, s0 + count, options.seed, options.first_sample, options.pixel_spp,
                      stats.local());
          if (progress) progress->add(count);
        }
      });
    });
    if (!pass_complete || stopped()) break;
    film.merge(pass);
    done += count;
    if (options.on_pass) options.on_pass(done);
    if (done < options.spp && options.stop_after_pass && options.stop_after_pass(film, done)) {
      result.stopped_after_pass = true;
      break;
    }
  }
  if (progress) progress->finish();
  result.samples_done = done;
  result.interrupted = done < options.spp && !result.stopped_after_pass;
  for (const PathStats& s : stats) {
    result.paths.paths += s.paths;
    result.paths.fluorescence_events += s.fluorescence_events;
    result.paths.excitation_rays += s.excitation_rays;
    result.paths.excitation_continuations += s.excitation_continuations;
    result.paths.excitation_routes += s.excitation_routes;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace chlorovdb
