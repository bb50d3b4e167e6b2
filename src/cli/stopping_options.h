#pragma once
// `render --target-error E [--target-region x0,y0,x1,y1] --time-limit S`: the
// command-line side of film/stopping_rule.h, kept apart so any render driver
// calls the same three functions (build the rule, check it per pass, record it).
#include <optional>
#include <string>

#include "checkpoint/partition.h"
#include "film/stopping_rule.h"
#include "io/image.h"

namespace chlorovdb::cli {

// The sample cap of `--target-error` when no --spp is given.
inline constexpr int kTargetErrorMaxSpp = 1 << 16;

// `region` in image pixels, within `crop` (it becomes film pixels). InputError
// names the option when the region is malformed or outside the crop, or when a
// target error is asked for under MPI (the ranks would stop at different counts).
StoppingRule make_stopping_rule(const std::optional<double>& target_error, const std::optional<std::string>& region,
                                const std::optional<double>& time_limit, const PixelWindow& crop, int mpi_ranks);

// Metadata stop_reason, and with a target: target_relative_error, relative_error (at the end).
void set_stop_metadata(Metadata& m, const StoppingRule& rule, const StopDecision& stopped, const Film& film, int samples_done);

std::string describe(const StopDecision& d);

}  // namespace chlorovdb::cli
