#pragma once
// Learns a scene's continuation guides (fluorescence/continuation_guide.h) from
// probe paths: in each cell of a coarse grid over a fluorescent medium, a few
// points inside the medium where the pigment is; from each, a few continuations
// (integrator/fluorescence_event.h, continuation_radiance) per direction bin,
// at a λ'' drawn as a continuation draws it. A bin's weight is the root mean
// square of v = λ''·ε(λ'')·L / p(λ''), the continuation's own integrand (the
// variance-optimal density for a noisy integrand is ∝ √E[v²]). Each cell's
// histogram is mixed with a quarter of the medium's mean one, so a cell whose
// few probes missed a bright direction still finds it sometimes.
//
// Deterministic (a fixed seed, one random stream per cell): a render depends
// only on its own seed and samples, whichever render trained the guide.
#include <vector>

#include "fluorescence/continuation_guide.h"
#include "scene/scene.h"

namespace chlorovdb {

struct GuideTraining {
  int cells_per_axis = 4;   // along the medium's longest axis (others in proportion, at least 1)
  int points_per_cell = 2;  // probe origins per cell
  int probes_per_bin = 4;   // continuations per direction bin and origin
  float uniform_share = 0.3f;  // of the guided direction density (ContinuationGuide)
  uint64_t seed = 0x67756964656dULL;
};

// One guide per medium of the scene (empty where nothing fluoresces or no
// bounded region holds the medium). Runs in the caller's TBB arena.
std::vector<ContinuationGuide> train_continuation_guides(const Scene& scene, const GuideTraining& training = {});

// Whether a render of this scene draws continuations from guides: full mode,
// guided directions, a fluorescent medium.
bool uses_continuation_guides(const Scene& scene);

// render() calls this first: trains scene.continuation_guides once (thread-safe)
// when uses_continuation_guides, and returns the seconds it took (0 if already trained).
double prepare_continuation_guides(const Scene& scene);

}  // namespace chlorovdb
