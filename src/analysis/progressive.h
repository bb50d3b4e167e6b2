#pragma once
// Convergence runs, on top of integrator/render.h: one progressive render that
// stops at each requested sample count and time budget to measure the error
// against a reference. It relies on render()'s determinism: sample s of pixel
// (x, y) depends only on (seed, x, y, s), so rendering [0, a) then [a, b) gives
// the same samples as [0, b). (References are render sessions: session/.)
#include <atomic>
#include <functional>
#include <vector>

#include "analysis/image_error.h"
#include "integrator/excitation_routes.h"
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
  ExcitationRouteSums excitation_routes;  // what excited the fluorescence, over the samples so far
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

}  // namespace chlorovdb
