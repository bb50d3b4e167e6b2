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
// Each route's identifier, in ExcitationRoute's order (the Python results' keys).
inline constexpr std::array<const char*, kExcitationRoutes> kExcitationRouteKeys = {
    "connection", "bounce", "continuation_light", "continuation_reemitted", "photons"};

// Per route, the sum of the events' contributions to the camera paths'
// fluorescence (each times its camera path's weight, averaged over the lanes the
// path carries: an event whose hero wavelength lies outside the emission band
// still counts by its other lanes), of their squares,
// and how many events it contributed to: the routes' shares of the fluorescence
// layer's mean and of its second moment per event, and how often each route
// finds anything (docs/fluorescence.md, "Where the excitation comes from").
// Counts are doubles: they are summed over ranks with the sums.
struct ExcitationRouteSums {
  std::array<double, kExcitationRoutes> sum{}, sum_squares{}, events{};
  double events_any = 0;  // events to which some route contributed
  // One event's contributions per route (0 where a route brought nothing).
  void add_event(const std::array<double, kExcitationRoutes>& value) {
    bool any = false;
    for (size_t r = 0; r < value.size(); ++r)
      if (value[r] != 0) sum[r] += value[r], sum_squares[r] += value[r] * value[r], events[r] += 1, any = true;
    events_any += any ? 1 : 0;
  }
  ExcitationRouteSums& operator+=(const ExcitationRouteSums& o) {
    for (size_t r = 0; r < sum.size(); ++r)
      sum[r] += o.sum[r], sum_squares[r] += o.sum_squares[r], events[r] += o.events[r];
    events_any += o.events_any;
    return *this;
  }
};

// One line for the render's report: each route's share of the sums' total and
// of their squares', and the share of the events it contributed to ("" when no
// event contributed).
std::string describe_excitation_routes(const ExcitationRouteSums& routes);

}  // namespace chlorovdb
