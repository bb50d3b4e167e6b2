#pragma once
// The render driver: progressive passes over tiles, in parallel with TBB.
// Every (pixel, sample) pair has its own random stream, so an image depends
// only on the seed and the sample range, never on the thread count or the
// order tiles finish in.
#include <atomic>
#include <functional>

#include "integrator/path_tracer.h"
#include "scene/scene.h"

namespace chlorovdb {

struct RenderOptions {
  int first_sample = 0;  // render samples [first_sample, first_sample + spp) of every pixel
  int spp = 1;
  int threads = 0;  // 0: all cores
  uint64_t seed = 0;
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (Ctrl-C): stop after the current tiles
  bool show_progress = false;
  // Called after each completed pass with the samples done so far (checkpoints).
  std::function<void(int samples_done)> on_pass;
};

struct RenderStats {
  double seconds = 0;
  int samples_done = 0;  // complete passes: every pixel has this many samples
  bool interrupted = false;
  PathStats paths;
};

// Film layer order used by the renderer.
enum FilmLayer { kLayerTotal = 0, kLayerFluorescence = 1, kLayerNonFluorescence = 2 };
std::vector<std::string> film_layer_names();

// Accumulates samples into `film`. An interrupted render keeps only complete
// passes, so the image it writes is unbiased with `samples_done` samples.
RenderStats render(const Scene& scene, Film& film, const RenderOptions& options);

// The per-sample random stream (exposed for tests).
Rng sample_rng(uint64_t seed, int x, int y, int sample);

}  // namespace chlorovdb
