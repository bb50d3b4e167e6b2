#include "integrator/excitation_routes.h"

#include <fmt/format.h>

namespace chlorovdb {

std::string describe_excitation_routes(const ExcitationRouteSums& routes) {
  static constexpr const char* kNames[kExcitationRoutes] = {"connection to the lights", "bounce connection",
                                                            "continuations' light", "re-emitted fluorescence",
                                                            "photon grid"};
  double total = 0, total_squares = 0;
  for (size_t r = 0; r < kExcitationRoutes; ++r) total += routes.sum[r], total_squares += routes.sum_squares[r];
  if (!(total > 0) || !(total_squares > 0)) return "";
  std::string line;
  for (size_t r = 0; r < kExcitationRoutes; ++r) {
    if (routes.sum_squares[r] == 0) continue;
    line += fmt::format("{}{} {:.1f} % / {:.1f} % (in {:.2g} % of events)", line.empty() ? "" : ", ", kNames[r],
                        100 * routes.sum[r] / total, 100 * routes.sum_squares[r] / total_squares,
                        100 * routes.events[r] / routes.events_any);
  }
  return line;
}

}  // namespace chlorovdb
