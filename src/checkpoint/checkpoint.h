#pragma once
// Checkpoints: a film's raw double-precision sums (every layer and the spectral
// bins) with what produced them, so a render can resume bit-exactly and partial
// renders can be merged without float rounding.
//
// File layout (little-endian), docs/distributed.md:
//   "CHLVDBCK"  u32 format version (3; 2 is read too: no AOVs)  u64 header length H
//   H bytes of JSON header (CheckpointHeader, plus layers, spectral bins, colour space, AOVs)
//   f64 sums: each layer's (y·w + x)·3 + {X,Y,Z}, then each layer's sums of squared RGB
//   (y·w + x)·3 + {R,G,B} (the standard-error layers), then (y·w + x)·bins + bin, then
//   with AOVs (y·w + x)·Film::kAovSums + i (Film::raw_aovs); w, h = the crop's size
//   u64 checksum of everything before it
// Written to "<file>.<pid>.tmp", flushed to disk and renamed over <file>: a crash
// (even SIGKILL) leaves either the previous checkpoint or the new one, never a torn file.
#include <cstdint>
#include <filesystem>
#include <string>

#include "checkpoint/partition.h"
#include "film/film.h"

namespace chlorovdb {

struct CheckpointHeader {
  std::string chlorovdb_version;
  std::string scene;  // absolute path when written (informative; the signature holds its hash)
  int full_width = 0, full_height = 0;
  PixelWindow crop;  // the film's pixels
  int sample_first = 0, sample_end = 0;  // the render's target: samples [first, end) of every pixel
  int samples_done = 0;                  // samples [first, first + done) are in the sums
  Signature signature;
  uint64_t nonfinite_samples = 0;  // dropped samples so far (the film's counter restarts at 0 on resume)
  double wall_time_s = 0;          // render time so far, over all sessions

  PartInfo part() const;  // the sums as a part of the full image
};

// `film` must have the crop's size. Throws InputError naming the file on I/O errors.
void write_checkpoint(const std::filesystem::path& file, const CheckpointHeader& header, const Film& film);

// True when the file starts with the checkpoint magic.
bool is_checkpoint(const std::filesystem::path& file);
// The header alone (cheap). Throws InputError naming the file and what is wrong.
CheckpointHeader read_checkpoint_header(const std::filesystem::path& file);
// Header and sums; the checksum is verified. The film's non-finite counter is 0:
// the count lives in header.nonfinite_samples.
Film read_checkpoint(const std::filesystem::path& file, CheckpointHeader* header);

// Adds `part` (sums of the pixels `window`) into `full` at the window's place.
// Films must agree on layers and spectral bins (std::invalid_argument otherwise).
void add_film_window(Film& full, const Film& part, const PixelWindow& window);
// Overwrites `film`'s sums with `sums` (same layout as raw_xyz / raw_spectral).
void set_raw_sums(Film& film, int layer, const std::vector<double>& sums);
void set_raw_rgb_squares(Film& film, int layer, const std::vector<double>& sums);
void set_raw_spectral(Film& film, const std::vector<double>& sums);
void set_raw_aovs(Film& film, const std::vector<double>& sums);

}  // namespace chlorovdb
