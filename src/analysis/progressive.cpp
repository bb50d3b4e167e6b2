#include "analysis/progressive.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <time.h>

#include <fmt/format.h>

#include "integrator/render.h"

namespace chlorovdb {

namespace {

Film make_film(const Scene& scene) {
  Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
  if (scene.settings.spectral_bins > 0) film.enable_spectral(kLambdaMin, kLambdaMax, scene.settings.spectral_bins);
  return film;
}

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

bool stopped(const std::atomic<bool>* stop) { return stop && stop->load(std::memory_order_relaxed); }

}  // namespace

std::vector<ConvergencePoint> run_convergence(const Scene& scene, const Image& reference, const ConvergenceOptions& o) {
  std::vector<int> spp = o.spp;
  std::sort(spp.begin(), spp.end());
  spp.erase(std::unique(spp.begin(), spp.end()), spp.end());
  std::erase_if(spp, [](int n) { return n < 1; });
  std::vector<double> budgets = o.time_budgets;
  std::sort(budgets.begin(), budgets.end());
  std::erase_if(budgets, [](double t) { return !(t > 0); });

  Film film = make_film(scene);
  std::vector<ConvergencePoint> points;
  int done = 0;
  double seconds = 0, cpu_seconds = 0;
  ExcitationRouteSums routes;
  auto elapsed = [&] { return o.clock == Clock::wall ? seconds : cpu_seconds; };
  size_t next_spp = 0, next_budget = 0;
  auto measure = [&](double budget) {
    ConvergencePoint p;
    p.spp = done;
    p.seconds = seconds;
    p.cpu_seconds = cpu_seconds;
    p.time_budget = budget;
    p.excitation_routes = routes;
    Image image = film.to_image(done);
    p.errors = image_errors(image, reference);
    if (o.keep_images) p.image = std::move(image);
    if (o.on_point) o.on_point(p);
    points.push_back(std::move(p));
  };
  while ((next_spp < spp.size() || next_budget < budgets.size()) && !stopped(o.stop)) {
    // Next chunk: up to the next sample count, and no further than ~90 % of
    // the time left to the next budget at the rate measured so far, so a
    // budget is overshot by at most about one sample per pixel.
    int chunk = next_spp < spp.size() ? spp[next_spp] - done : (1 << 30);
    if (next_budget < budgets.size()) {
      const double per_sample = done > 0 ? elapsed() / done : 0.0;
      const double left = budgets[next_budget] - elapsed();
      const int by_time = per_sample > 0 ? int(std::clamp(std::floor(0.9 * left / per_sample), 1.0, 1e6)) : 1;
      chunk = std::min(chunk, by_time);
    }
    RenderOptions ro;
    ro.first_sample = done;
    ro.spp = std::max(1, chunk);
    ro.threads = o.threads;
    ro.seed = o.seed;
    ro.stop = o.stop;
    const double cpu0 = process_cpu_seconds();
    const RenderStats stats = render(scene, film, ro);
    cpu_seconds += process_cpu_seconds() - cpu0;
    done += stats.samples_done;
    seconds += stats.seconds;
    routes += stats.paths.excitation_routes;
    if (stats.interrupted) break;
    while (next_spp < spp.size() && spp[next_spp] <= done) {
      measure(0.0);
      ++next_spp;
    }
    while (next_budget < budgets.size() && budgets[next_budget] <= elapsed()) {
      measure(budgets[next_budget]);
      ++next_budget;
    }
  }
  return points;
}

}  // namespace chlorovdb
