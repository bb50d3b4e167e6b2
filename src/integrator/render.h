#pragma once
// The render driver: progressive passes over tiles, in parallel with TBB.
// Every (pixel, sample) pair has its own random stream, so an image depends
// only on the seed and the sample range, never on the thread count or the
// order tiles finish in.
//
// Summation order, which makes resumed renders bit-identical: a pass renders
// samples [s0, s1) of every pixel into a zeroed pass film, each pixel's samples
// in increasing index; the completed pass is then added to `film`. Pass sizes
// depend only on the number of samples done (1, 1, 2, 4, 8, 8, ...), so a render
// resumed after k complete passes (samples_done) performs the same additions in
// the same order as one that never stopped.
#include <atomic>
#include <functional>

#include "integrator/path_tracer.h"
#include "scene/scene.h"

namespace chlorovdb {

struct RenderOptions {
  int first_sample = 0;  // render samples [first_sample, first_sample + spp) of every pixel
  int spp = 1;
  // Resume: samples [first_sample, first_sample + samples_done) are already in
  // `film` (from a checkpoint written at a pass boundary); continue after them.
  int samples_done = 0;
  // Crop: the film covers image pixels [film_x0, film_x0 + film.width()) x
  // [film_y0, film_y0 + film.height()); pixel (x, y) goes to film pixel
  // (x - film_x0, y - film_y0) and keeps its own random streams.
  int film_x0 = 0, film_y0 = 0;
  int threads = 0;  // 0: all cores
  uint64_t seed = 0;
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (Ctrl-C): stop after the current tiles
  bool show_progress = false;
  // Called after each completed pass, once `film` holds it, with the samples
  // done so far (counted from first_sample): the moment to write a checkpoint.
  std::function<void(int samples_done)> on_pass;
  // Called after on_pass: true ends the render there (not an interruption), e.g.
  // film/stopping_rule.h's check_stop for --target-error and --time-limit.
  std::function<bool(const Film& film, int samples_done)> stop_after_pass;
  // Adaptive sampling (film/adaptive.h): film pixel p renders only samples
  // [first_sample, first_sample + (*pixel_spp)[p]); passes skip pixels past their
  // count. The film must count samples (Film::enable_sample_counts).
  const std::vector<int>* pixel_spp = nullptr;
};

struct RenderStats {
  double seconds = 0;
  int samples_done = 0;  // complete passes: every pixel has this many samples (including options.samples_done; at most its pixel_spp)
  bool interrupted = false;
  bool stopped_after_pass = false;  // stop_after_pass ended the render before spp
  PathStats paths;
};

// Film layer order used by the renderer.
enum FilmLayer { kLayerTotal = 0, kLayerFluorescence = 1, kLayerNonFluorescence = 2 };
std::vector<std::string> film_layer_names();

// Accumulates samples into `film`. An interrupted render keeps only complete
// passes, so the image it writes is unbiased with `samples_done` samples.
// Throws std::invalid_argument when the film (with its offset) does not fit the
// image or samples_done is outside [0, spp].
RenderStats render(const Scene& scene, Film& film, const RenderOptions& options);

// Samples in the pass that starts after `done` of `total` (the fixed schedule above).
int pass_size(int done, int total);

// The per-sample random stream (exposed for tests).
Rng sample_rng(uint64_t seed, int x, int y, int sample);

}  // namespace chlorovdb
