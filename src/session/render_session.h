#pragma once
// One render of a loaded scene as every front end runs it (`chlorovdb render`,
// `reference`, chlorovdb-mpi, the Python module): which samples and pixels,
// when to stop (Ctrl-C, the caller's poll, a per-pass stopping rule), the
// checkpoint and resume, the sum over MPI ranks, and the output's metadata.
// docs/distributed.md describes checkpoints, crops and sample ranges.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "checkpoint/partition.h"
#include "film/adaptive.h"
#include "film/film.h"
#include "integrator/render.h"
#include "io/image.h"
#include "scene/scene.h"

namespace chlorovdb {

// This process's share of the work: rank r of `size` renders the r-th slice of
// the sample range; `sum_to_root` adds a vector over the ranks into rank 0's
// copy (MPI_Reduce; unused with one rank).
struct RankGroup {
  int rank = 0, size = 1;
  std::function<void(std::vector<double>&)> sum_to_root;
};

struct RenderJob {
  std::optional<SampleRange> samples;  // default [0, scene spp)
  std::optional<PixelWindow> crop;     // default the whole image
  std::optional<uint64_t> seed;        // default the scene's
  std::optional<ColorSpace> color_space;
  std::optional<int> spectral_bins;
  int threads = 0;  // 0: all cores
  bool show_progress = false;
  // What the signature's scene_hash identifies (the scene file's hash, plus any
  // edits): checkpoints and parts of another scene are refused.
  std::string scene_hash;
  // Checkpoint (empty: none): the raw sums, every checkpoint_every seconds at a
  // pass boundary (0: every pass), when stopped and at the end; one file per
  // rank ("<file>.rank<r>of<n>"). An existing file is refused unless `resume`.
  std::filesystem::path checkpoint;
  double checkpoint_every = 300;
  bool resume = false;
  // Stop requests, all checked between passes (and `interrupt` also between tiles):
  const std::atomic<bool>* interrupt = nullptr;  // asynchronous (a signal handler)
  std::function<bool()> poll_interrupt;          // e.g. Python's pending KeyboardInterrupt
  // A stopping rule on the film so far (not an interruption: the render ends as done).
  std::function<bool(const Film& film, int samples_done)> stop_after_pass;
  // After each checkpoint write (and the last), with the film then: `reference`
  // rewrites its EXR there.
  std::function<void(const Film& film, int samples_done)> on_checkpoint;
  RankGroup ranks;
  // Adaptive sampling (film/adaptive.h): a pilot from its own streams, then
  // exactly its n_p samples per pixel from the range's first sample, capped by
  // the range's size (which replaces adaptive->max_spp). InputError with several
  // ranks or a checkpoint: they would have to carry the pilot's counts.
  std::optional<AdaptiveSampling> adaptive;
};

struct RenderOutcome {
  Film film;              // on rank 0: the sum over all ranks
  SampleRange range{};    // the samples requested of every pixel
  PixelWindow crop{};
  PartInfo part{};        // the samples actually in `film`, the signature
  int samples_done = 0;   // per pixel, over all ranks
  int resumed_at = 0;     // this rank's samples that came from the checkpoint
  bool interrupted = false;
  bool stopped_by_rule = false;
  double seconds = 0;           // over all sessions of a resumed render (the slowest rank)
  double session_seconds = 0;   // this run's
  uint64_t nonfinite_samples = 0;
  int pilot_spp = 0;  // adaptive: the pilot's samples per pixel (not in `film`)
  PathStats paths{};  // summed over the ranks
  std::filesystem::path checkpoint{};  // this rank's file (empty: none)
  bool root() const { return rank == 0; }
  int rank = 0, ranks = 1;
};

// Renders `scene` as `job` says. Throws InputError for a bad checkpoint or job.
RenderOutcome run_render_session(const Scene& scene, const RenderJob& job);

// `film` holding `samples_done` samples per pixel as an image with the
// metadata that does not depend on the outcome (spp, seed, version, scene, ...).
Image film_image(const Scene& scene, const RenderJob& job, const Film& film, int samples_done);

// The film as an image with the session's metadata (spp, seed, wall time,
// scene, part, ...). `outcome.samples_done` must be > 0.
Image session_image(const Scene& scene, const RenderJob& job, const RenderOutcome& outcome);

// RenderJob::scene_hash of a scene file loaded with `sets` edits (the file's
// hash alone without edits, so plain renders' parts keep matching).
std::string scene_hash(const std::filesystem::path& file, std::span<const std::string> sets = {});

// The effective settings of a job: what the signature and metadata report.
uint64_t job_seed(const Scene& scene, const RenderJob& job);

}  // namespace chlorovdb
