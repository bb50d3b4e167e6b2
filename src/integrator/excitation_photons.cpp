#include "integrator/excitation_photons.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>

#include "core/sampling.h"
#include "integrator/medium_region.h"
#include "integrator/transport.h"
#include "lights/light_emission.h"
#include "materials/bsdf.h"
#include "media/pigment.h"
#include "tracking/sample_t_maj.h"

namespace chlorovdb {

namespace {

// Photons are traced in this many chunks, each into its own grid, summed in order.
constexpr int kChunks = 8;
// Far enough to leave any region a flight in an unbounded medium could cross.
constexpr float kFarAway = 1e6f;

// One photon of pigment fp (in `medium`) from its lights, adding its flights
// through `medium` to `grid`. Absorbed by fp, it is re-emitted (weight Q, λ from
// `emission`, isotropic) and goes on: the pigment's own fluorescence excites it
// too where emission and absorption overlap (chlorophyll's red band).
void trace_photon(const Scene& scene, int medium, const FluorescentPigment& fp, const ExcitationSampler& emission,
                  const EmissionTarget& target, const PhotonTracing& tracing, ExcitationGrid& grid, Rng& rng) {
  const auto pick = fp.light_sampler.sample(rng.uniform());
  if (!pick) return;
  const ExcitationSampler& es = fp.excitation[size_t(fp.slot_of_light(pick->index))];
  if (!es.can_excite()) return;
  float pdf_lambda = 0.f;
  const float lp = es.sample(rng.uniform(), &pdf_lambda);
  const float eps = fp.epsilon(lp);
  if (!(pdf_lambda > 0.f) || !(eps > 0.f)) return;
  const Point2 u_position{rng.uniform(), rng.uniform()}, u_direction{rng.uniform(), rng.uniform()};
  const auto emitted = sample_emission(scene.lights[size_t(pick->index)], u_position, u_direction, lp, scene.geometry,
                                       &target, rng.uniform());
  if (!emitted) return;
  // Power carried, W: the light's flux sample over the choice of light and λ'.
  float w = emitted->flux / (pick->pmf * pdf_lambda);
  const float w_start = w;
  float lambda = lp;
  float per_length = lp * eps;  // the tally's λ'·ε(λ') per metre of flight, times w
  int bin = ExcitationGrid::bin_of(lp);

  SampledWavelengths wl = SampledWavelengths::single(lp);
  std::optional<PreparedMedia> media(std::in_place, scene, wl);
  Ray ray = emitted->ray;
  int current = medium_at(scene, ray.o);
  for (int bounce = 0; bounce < tracing.max_bounces; ++bounce) {
    const auto hit = scene.geometry.intersect(ray, kInfinity);
    const float t_end = hit ? hit->t : kInfinity;
    if (current >= 0) {
      bool absorbed = false, scattered = false, by_pigment = false;
      Vec3 collision, scattered_dir;
      sample_T_maj(ray, t_end, rng.uniform(), rng, wl, scene.media[size_t(current)], (*media)[current],
                   [&](const Vec3& p, const MediumCollision& c, const SampledSpectrum& sigma_maj,
                       const MajorantTransmittance&) {
                     const float sigma_t = c.sigma_t(0), sigma_s = c.sigma_s(0);
                     const float u = rng.uniform() * sigma_maj[0];
                     if (u >= sigma_t) return true;  // null collision
                     collision = p;
                     if (u < sigma_t - sigma_s) {
                       absorbed = true;
                       if (current == medium) {  // by fp with probability μ_fp / σ_a
                         const float mu_fp =
                             kAbsorptionPerMolarExtinction * fp.epsilon(lambda) * c.properties().concentration[size_t(fp.pigment)];
                         by_pigment = rng.uniform() * (sigma_t - sigma_s) < mu_fp;
                       }
                       return false;
                     }
                     const MediumScattering ms = c.scattering();
                     const MediumPhaseSample ps = phase_sample(ms.phase, -ray.d, Point2{rng.uniform(), rng.uniform()});
                     if (!(ps.pdf > 0.f)) {
                       absorbed = true;
                       return false;
                     }
                     w *= ps.p[0] / ps.pdf;
                     scattered_dir = ps.wi;
                     scattered = true;
                     return false;
                   });
      if (current == medium) {
        const Vec3 end = absorbed || scattered ? collision : ray.at(std::min(t_end, kFarAway));
        grid.deposit(ray.o, end, bin, w * per_length);
      }
      if (absorbed && by_pigment && emission.can_excite()) {
        // Re-emission: photons out per photon in is Q·r(λ', λ) f(λ) per nm, so the
        // power carried changes by Q·r·f(λ)·(λ'/λ) / p(λ) for λ drawn with pdf p.
        float pdf_emitted = 0.f;
        const float emitted_lambda = emission.sample(rng.uniform(), &pdf_emitted);
        w *= fp.quantum_yield * fp.redistribution(lambda, emitted_lambda) * fp.emission(emitted_lambda) *
             (lambda / emitted_lambda) / pdf_emitted;
        lambda = emitted_lambda;
        per_length = lambda * fp.epsilon(lambda);
        bin = ExcitationGrid::bin_of(lambda);
        wl = SampledWavelengths::single(lambda);
        media.emplace(scene, wl);
        ray = Ray{collision, sample_uniform_sphere(Point2{rng.uniform(), rng.uniform()})};
        if (!(w > 0.f)) return;
        continue;
      }
      if (absorbed || !(w > 0.f)) return;
      if (scattered) {
        ray = Ray{collision, scattered_dir};
        continue;
      }
    }
    if (!hit) return;
    const ShapeBinding& binding = scene.shapes[size_t(hit->shape_id)];
    if (is_pass_through(scene, binding)) {
      current = medium_after_crossing(binding, hit->ng, ray.d);
      ray = scene.geometry.spawn_ray(*hit, ray.d);
      continue;
    }
    const Bsdf bsdf = make_bsdf(scene.materials[size_t(binding.material)], *hit, wl);
    const auto bs = bsdf.sample(-ray.d, rng.uniform(), Point2{rng.uniform(), rng.uniform()});
    if (!bs || !(bs->pdf > 0.f)) return;
    w *= bs->f[0] * std::fabs(dot(bs->wi, hit->ns)) / bs->pdf;
    // The BSDF is written for radiance, which a refraction compresses by 1/η²;
    // a photon's power is not compressed.
    if (bs->is_transmission) w *= bs->eta * bs->eta;
    current = dot(bs->wi, hit->ng) < 0.f ? binding.medium_inside : binding.medium_outside;
    ray = scene.geometry.spawn_ray(*hit, bs->wi);
    // Russian roulette once the photon has lost power (glass and a bright floor keep most of it).
    if (bounce > 1 && w < w_start) {
      const float p_survive = std::max(0.05f, w / w_start);
      if (!(rng.uniform() < p_survive)) return;
      w /= p_survive;
    }
    if (!(w > 0.f)) return;
  }
}

// The volume `medium` fills in each cell: lines along x, kLines² per row of cells
// (jittered in y and z: fixed offsets would count a wall between two of them as
// wherever the nearer line is, 13 % off in a slab's outer cells), walked through
// the scene's surfaces (each crossing changes the medium as it would for a photon).
void measure_medium_volume(const Scene& scene, int medium, ExcitationGrid& grid, Rng& rng) {
  constexpr int kLines = 8;
  constexpr int kMaxCrossings = 100000;
  const Bounds3& region = grid.region();
  const std::array<int, 3> n = grid.cells();
  const Vec3 size = region.diagonal();
  const float dy = size.y / float(n[1] * kLines), dz = size.z / float(n[2] * kLines);
  for (int j = 0; j < n[1] * kLines; ++j)
    for (int k = 0; k < n[2] * kLines; ++k) {
      const Vec3 start{region.lo.x, region.lo.y + (float(j) + rng.uniform()) * dy,
                       region.lo.z + (float(k) + rng.uniform()) * dz};
      int current = medium_at(scene, start);
      Ray ray{start, Vec3{1.f, 0.f, 0.f}};
      for (int crossing = 0; crossing < kMaxCrossings; ++crossing) {
        const float remaining = region.hi.x - ray.o.x;
        if (!(remaining > 0.f)) break;
        const auto hit = scene.geometry.intersect(ray, remaining);
        const Vec3 stop = hit ? hit->p : Vec3{region.hi.x, ray.o.y, ray.o.z};
        if (current == medium) grid.add_medium_volume(ray.o, stop, dy * dz);
        if (!hit) break;
        const ShapeBinding& binding = scene.shapes[size_t(hit->shape_id)];
        current = dot(ray.d, hit->ng) < 0.f ? binding.medium_inside : binding.medium_outside;
        ray = scene.geometry.spawn_ray(*hit, ray.d);
      }
    }
}

// The standard error of each cell's summed tally from the independent chunks:
// the variance of a sum of K chunk tallies is K times their sample variance.
std::vector<float> tally_errors_from_chunks(const std::vector<ExcitationGrid>& chunks) {
  const size_t K = chunks.size();
  if (K < 2) return {};
  std::vector<float> errors(chunks[0].cell_count());
  std::vector<double> t(K);
  for (size_t c = 0; c < errors.size(); ++c) {
    double sum = 0;
    for (size_t k = 0; k < K; ++k) sum += t[k] = chunks[k].cell_total(c);
    const double mean = sum / double(K);
    double deviations = 0;
    for (double x : t) deviations += (x - mean) * (x - mean);
    errors[c] = float(std::sqrt(double(K) * deviations / double(K - 1)));
  }
  return errors;
}

ExcitationGrid trace_pigment(const Scene& scene, int medium, int k, const PhotonTracing& tracing,
                             const std::atomic<bool>* stop) {
  const FluorescentPigment& fp = scene.fluorescence[size_t(medium)][size_t(k)];
  Bounds3 region = medium_region(scene, medium);
  if (region.empty() || !fp.excitation_possible() || tracing.photons < 1) return {};
  // medium_region samples the surfaces on a lattice, so it can fall short of the
  // extreme points: widen it (an event outside the grid would read no excitation).
  const Vec3 pad = region.diagonal() * 0.02f + Vec3(1e-6f);
  region.lo = region.lo - pad;
  region.hi = region.hi + pad;
  // Cells in proportion to the region, but at least 8 (or cells_per_axis) across
  // its thin axes: a leaf or a spill is a thin layer, and its fluence falls across it.
  std::array<int, 3> cells = cell_counts(region, std::max(1, tracing.cells_per_axis));
  for (int& n : cells) n = std::max(n, std::min(8, tracing.cells_per_axis));
  std::vector<ExcitationGrid> chunks(kChunks, ExcitationGrid(region, cells));
  // Re-emitted wavelengths: ∝ the emission spectrum (times λ; the weight corrects for it).
  const ExcitationSampler emission(fp.emission, Spectrum::constant(1.f));
  const EmissionTarget target{region.center(), 0.5f * length(region.diagonal()), tracing.aimed_share};
  tbb::parallel_for(0, kChunks, [&](int chunk) {
    const int64_t first = tracing.photons * chunk / kChunks, last = tracing.photons * (chunk + 1) / kChunks;
    const uint64_t stream = hash_combine(hash_combine(uint64_t(medium), uint64_t(k)), uint64_t(chunk));
    Rng rng(hash_combine(tracing.seed, stream), mix_bits(tracing.seed));
    for (int64_t i = first; i < last; ++i) {
      if (stop && (i & 4095) == 0 && stop->load(std::memory_order_relaxed)) return;
      trace_photon(scene, medium, fp, emission, target, tracing, chunks[size_t(chunk)], rng);
    }
  });
  std::vector<float> errors = tally_errors_from_chunks(chunks);
  ExcitationGrid grid = std::move(chunks[0]);
  for (int c = 1; c < kChunks; ++c) grid.add(chunks[size_t(c)]);
  grid.set_tally_errors(std::move(errors));
  Rng lines(hash_combine(tracing.seed, hash_combine(uint64_t(medium), uint64_t(k))), 0);
  measure_medium_volume(scene, medium, grid, lines);
  grid.normalize(double(tracing.photons));
  return grid;
}

}  // namespace

std::optional<std::vector<std::vector<ExcitationGrid>>> trace_excitation_photons(const Scene& scene,
                                                                                const PhotonTracing& tracing,
                                                                                const std::atomic<bool>* stop) {
  std::vector<std::vector<ExcitationGrid>> grids(scene.media.size());
  for (size_t m = 0; m < scene.media.size(); ++m)
    for (size_t k = 0; k < scene.fluorescence[m].size(); ++k)
      grids[m].push_back(trace_pigment(scene, int(m), int(k), tracing, stop));
  if (stop && stop->load(std::memory_order_relaxed)) return std::nullopt;
  return grids;
}

std::string describe_excitation_photons(const RenderSettings& s) {
  return fmt::format("{} photons per pigment, {:g}% aimed, {} cells", s.excitation_photons,
                     100.f * s.excitation_photons_aimed, s.excitation_grid_cells);
}

float excitation_grid_error(const Scene& scene) {
  float worst = 0.f;
  if (scene.excitation_grids)
    for (const auto& per_medium : *scene.excitation_grids)
      for (const ExcitationGrid& g : per_medium) worst = std::max(worst, g.relative_error());
  return worst;
}

bool uses_excitation_photons(const Scene& scene) {
  return scene.settings.excitation_estimate == ExcitationEstimate::photons &&
         (scene.settings.fluorescence == FluorescenceMode::direct ||
          scene.settings.fluorescence == FluorescenceMode::full) &&
         scene.has_fluorescence();
}

double prepare_excitation_grids(const Scene& scene, uint64_t seed, const std::atomic<bool>* stop) {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  if (scene.excitation_grids || !uses_excitation_photons(scene)) return 0.0;
  const auto start = std::chrono::steady_clock::now();
  PhotonTracing tracing;
  tracing.photons = scene.settings.excitation_photons;
  tracing.cells_per_axis = scene.settings.excitation_grid_cells;
  tracing.aimed_share = scene.settings.excitation_photons_aimed;
  tracing.seed = hash_combine(tracing.seed, seed);
  if (auto grids = trace_excitation_photons(scene, tracing, stop))
    scene.excitation_grids = std::make_shared<const std::vector<std::vector<ExcitationGrid>>>(std::move(*grids));
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace chlorovdb
