#include "cli/stopping_options.h"

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb::cli {

StoppingRule make_stopping_rule(const std::optional<double>& target_error, const std::optional<std::string>& region,
                                const std::optional<double>& time_limit, const PixelWindow& crop, int mpi_ranks) {
  StoppingRule rule;
  rule.target_relative_error = target_error;
  rule.time_limit_s = time_limit;
  if (target_error && mpi_ranks > 1)
    throw InputError("command line", "--target-error", fmt::format("{}", *target_error),
                     "not available under MPI (each rank would stop at its own count); use --spp");
  if (region) {
    const PixelWindow w = parse_crop(*region, crop.x1, crop.y1, "--target-region");
    if (w.x0 < crop.x0 || w.y0 < crop.y0)
      throw InputError("command line", "--target-region", *region, fmt::format("lies outside the rendered crop {}", to_string(crop)));
    rule.region = PixelRegion{w.x0 - crop.x0, w.y0 - crop.y0, w.x1 - crop.x0, w.y1 - crop.y0};
  }
  return rule;
}

void set_stop_metadata(Metadata& m, const StoppingRule& rule, const StopDecision& stopped, const Film& film, int samples_done) {
  m.set("stop_reason", to_string(stopped.reason));
  if (!rule.target_relative_error || samples_done < 2) return;
  m.set("target_relative_error", *rule.target_relative_error);
  m.set("relative_error", relative_standard_error(film, samples_done, rule.region));
}

std::string describe(const StopDecision& d) {
  if (d.reason == StopReason::target_error) return fmt::format("{} (relative standard error {:.4g})", to_string(d.reason), d.relative_error);
  return to_string(d.reason);
}

}  // namespace chlorovdb::cli
