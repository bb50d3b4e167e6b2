#pragma once
#include <array>
#include <string>

namespace chlorovdb {

// What excites the fluorescence the camera sees, split by the strategy that
// estimated it at the camera paths' events: the excitation connection to the
// lights (through glass where it solves the path), the bounce connection (lit
// surfaces), and full mode's continuation, which brings light (scattered,
// reflected, refracted, or reaching the lights by paths the connections leave
// to it) or fluorescence re-emitted elsewhere (reabsorption); or, with
// excitation_estimate = photons, the photons' grid alone.
enum class ExcitationRoute { connection, bounce, continuation_light, continuation_reemitted, photons };
constexpr int kExcitationRoutes = 5;

// Per route, the sum of the events' hero-wavelength contributions to the camera
// paths' fluorescence (each times its camera path's weight) and of their
// squares: the routes' shares of the fluorescence layer's mean and of its
// second moment per event (docs/fluorescence.md, "Where the excitation comes from").
struct ExcitationRouteSums {
  std::array<double, kExcitationRoutes> sum{}, sum_squares{};
  void add(ExcitationRoute route, double value) {
    sum[size_t(route)] += value;
    sum_squares[size_t(route)] += value * value;
  }
  ExcitationRouteSums& operator+=(const ExcitationRouteSums& o) {
    for (size_t r = 0; r < sum.size(); ++r) sum[r] += o.sum[r], sum_squares[r] += o.sum_squares[r];
    return *this;
  }
};

// One line for the render's report: each route's share of the sums' total and
// of their squares' ("" when no event contributed).
std::string describe_excitation_routes(const ExcitationRouteSums& routes);

}  // namespace chlorovdb
