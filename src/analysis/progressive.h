#pragma once
// Rendering at increasing effort, on top of integrator/render.h:
//  - convergence runs: one progressive render that stops at each requested
//    sample count and time budget to measure the error against a reference;
//  - references: a long render that checkpoints as it goes and resumes from
//    its own partial output.
// Both rely on render()'s determinism: sample s of pixel (x, y) depends only on
// (seed, x, y, s), so rendering [0, a) then [a, b) gives the same samples as [0, b).
#include <atomic>
#include <functional>
#include <vector>

#include "analysis/image_error.h"
#include "io/image.h"
#include "scene/scene.h"

namespace chlorovdb {

// Which time budgets and efficiencies are measured in. Wall time is what a user
// waits; process CPU time (summed over threads) is what a shared machine's
// other load does not distort, and ranks estimators the same on an idle one.
enum class Clock { wall, cpu };

struct ConvergencePoint {
  int spp = 0;
  double seconds = 0;        // wall time of the rendering alone (no loading, no error computation)
  double cpu_seconds = 0;    // process CPU time over the same renders
  double time_budget = 0;    // the budget this point answers (0: a sample-count point), in options.clock
  double time(Clock c) const { return c == Clock::wall ? seconds : cpu_seconds; }
  std::vector<LayerError> errors;
  Image image;               // the estimate at this point
};

struct ConvergenceOptions {
  std::vector<int> spp;                // sample counts at which to measure
  std::vector<double> time_budgets;    // seconds of rendering at which to measure (the first pass boundary after each)
  Clock clock = Clock::wall;           // what the budgets count
  int threads = 0;                     // 0: all cores
  uint64_t seed = 0;
  const std::atomic<bool>* stop = nullptr;
  bool keep_images = false;            // fill ConvergencePoint::image
  std::function<void(const ConvergencePoint&)> on_point;  // called as each point is measured
};

// One progressive render of `scene` measured against `reference` at every
// requested sample count and time budget, in order of effort. Stops early
// (returning the points so far) when *stop is set.
std::vector<ConvergencePoint> run_convergence(const Scene& scene, const Image& reference, const ConvergenceOptions& options);

struct ReferenceOptions {
  int spp = 1024;                 // total samples per pixel wanted
  int threads = 0;
  uint64_t seed = 0;
  double checkpoint_seconds = 60; // write at the first pass boundary after this much time since the last write (0: every pass)
  const std::atomic<bool>* stop = nullptr;
  bool show_progress = false;
};

struct ReferenceResult {
  Image image;         // mean over spp_done samples
  int spp_done = 0;
  double seconds = 0;  // this session's rendering time
  bool interrupted = false;
};

// Renders samples [previous_spp, options.spp) and averages them with `previous`
// (the mean of samples [0, previous_spp), or nullptr when previous_spp = 0),
// weighted by sample counts. `checkpoint(image, spp_done)` is called at the
// checkpoint interval and once at the end with the combined mean so far.
ReferenceResult continue_reference(const Scene& scene, const Image* previous, int previous_spp,
                                   const ReferenceOptions& options,
                                   const std::function<void(const Image&, int spp_done)>& checkpoint);

// (n_a a + n_b b) / (n_a + n_b), layer by layer (layers of `a` matched by name
// in `b`); metadata from `b`. Throws std::invalid_argument on a size or layer mismatch.
Image combine_means(const Image& a, int n_a, const Image& b, int n_b);

}  // namespace chlorovdb
