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
  auto elapsed = [&] { return o.clock == Clock::wall ? seconds : cpu_seconds; };
  size_t next_spp = 0, next_budget = 0;
  auto measure = [&](double budget) {
    ConvergencePoint p;
    p.spp = done;
    p.seconds = seconds;
    p.cpu_seconds = cpu_seconds;
    p.time_budget = budget;
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

Image combine_means(const Image& a, int n_a, const Image& b, int n_b) {
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument(fmt::format("cannot combine a {}x{} image with a {}x{} one", a.width, a.height, b.width, b.height));
  if (n_a < 0 || n_b < 0 || n_a + n_b == 0) throw std::invalid_argument("combine_means needs positive sample counts");
  Image r = b;
  const double wa = double(n_a) / (n_a + n_b), wb = double(n_b) / (n_a + n_b);
  auto layer_of = [](const Image& image, std::string_view name) {
    const ImageLayer* l = image.find_layer(name);
    if (!l) throw std::invalid_argument(fmt::format("cannot combine images: layer '{}' is missing", name));
    return l;
  };
  for (ImageLayer& lb : r.layers) {
    const ImageLayer* la = layer_of(a, lb.name);
    if (la->channels != lb.channels || la->pixels.size() != lb.pixels.size())
      throw std::invalid_argument("cannot combine images: layer '" + lb.name + "' differs or is missing");
    if (!is_stderr_layer(lb.name)) {
      for (size_t i = 0; i < lb.pixels.size(); ++i) lb.pixels[i] = float(wa * la->pixels[i] + wb * lb.pixels[i]);
      continue;
    }
    // A standard error combines through both parts' sums of squares, so it needs both parts' means.
    const ImageLayer *ma = layer_of(a, stderr_base_name(lb.name)), *mb = layer_of(b, stderr_base_name(lb.name));
    if (ma->pixels.size() != lb.pixels.size() || mb->pixels.size() != lb.pixels.size())
      throw std::invalid_argument("cannot combine images: layer '" + lb.name + "' does not match its mean layer");
    for (size_t i = 0; i < lb.pixels.size(); ++i) {
      const double sum2 = sum_of_squares(ma->pixels[i], la->pixels[i], n_a) + sum_of_squares(mb->pixels[i], lb.pixels[i], n_b);
      lb.pixels[i] = float(standard_error(wa * ma->pixels[i] + wb * mb->pixels[i], sum2, n_a + n_b));
    }
  }
  if (r.layers.size() != a.layers.size()) throw std::invalid_argument("cannot combine images with different layers");
  return r;
}

ReferenceResult continue_reference(const Scene& scene, const Image* previous, int previous_spp,
                                   const ReferenceOptions& o,
                                   const std::function<void(const Image&, int spp_done)>& checkpoint) {
  if (previous_spp > 0 && !previous) throw std::invalid_argument("continue_reference: previous samples without an image");
  ReferenceResult result;
  result.spp_done = previous_spp;
  if (previous) result.image = *previous;
  if (previous_spp >= o.spp) return result;

  Film film = make_film(scene);
  auto combined = [&](int new_samples) {
    Image fresh = film.to_image(new_samples);
    return previous_spp > 0 ? combine_means(*previous, previous_spp, fresh, new_samples) : fresh;
  };
  using Clock = std::chrono::steady_clock;
  Clock::time_point last_write = Clock::now();
  RenderOptions ro;
  ro.first_sample = previous_spp;
  ro.spp = o.spp - previous_spp;
  ro.threads = o.threads;
  ro.seed = o.seed;
  ro.stop = o.stop;
  ro.show_progress = o.show_progress;
  ro.on_pass = [&](int done) {
    if (done == ro.spp) return;  // the final write follows
    if (std::chrono::duration<double>(Clock::now() - last_write).count() < o.checkpoint_seconds) return;
    if (checkpoint) checkpoint(combined(done), previous_spp + done);
    last_write = Clock::now();
  };
  const RenderStats stats = render(scene, film, ro);
  result.seconds = stats.seconds;
  result.interrupted = stats.interrupted;
  if (stats.samples_done > 0) {
    result.image = combined(stats.samples_done);
    result.spp_done = previous_spp + stats.samples_done;
    if (checkpoint) checkpoint(result.image, result.spp_done);
  }
  return result;
}

}  // namespace chlorovdb
