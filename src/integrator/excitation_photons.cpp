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

// An unbiased estimate of ∫ c_k along y0→y1 (m·mol/L) from one lookup, at a point
// drawn in proportion to the majorant grid's bound on c_k: a pigment that fills a
// sliver of the segment (a leaf's blade in a photon cell) is found by every draw,
// where a point drawn uniformly found it in a few per cent of them.
ExcitationGrid::LineIntegral pigment_along(const Medium& m, int k, const Vec3& y0, const Vec3& y1, float u) {
  const float length = distance(y0, y1);
  if (!(length > 0.f)) return {};
  const Ray ray_index = m.index_ray(Ray{y0, y1 - y0});  // t in [0, 1] from y0 to y1
  double total = 0;  // ∫ c_max dt
  for (MajorantIterator it = m.majorants(ray_index, 1.f); const auto s = it.next();)
    total += double(m.pigment_concentration_max(*s, k)) * (s->t_max - s->t_min);
  if (!(total > 0.0)) return {};
  double target = double(u) * total;
  for (MajorantIterator it = m.majorants(ray_index, 1.f); const auto s = it.next();) {
    const double c_max = m.pigment_concentration_max(*s, k), share = c_max * (s->t_max - s->t_min);
    if (!(share > 0.0)) continue;
    if (target >= share) {
      target -= share;
      continue;
    }
    const float t = s->t_min + float(target / c_max);
    const Vec3 y = y0 + t * (y1 - y0);
    const float c = m.pigment_concentration(m.channel_values(ray_index.at(t)), k);
    return {float(double(length) * total * c / c_max), y};
  }
  return {};  // rounding left the target past the last segment: a measure-zero miss
}

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
        if (grid.measure() == ExcitationGrid::Measure::amount) {
          grid.deposit_weighted(ray.o, end, bin, w * per_length, [&](const Vec3& y0, const Vec3& y1) {
            return pigment_along(scene.media[size_t(medium)], fp.pigment, y0, y1, rng.uniform());
          });
        } else {
          grid.deposit(ray.o, end, bin, w * per_length);
        }
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

// One axis of a voxel's interpolation kernel (the tent 1 − |u| over |u| < 1, or
// the box over |u| < 1/2; u in voxels from the centre) cut at its centre and at
// the faces of the grid's cells: each part's share of the kernel's mass, its
// centroid and half-width, in voxels about the centre.
struct KernelPart {
  float share, centroid, half;
};
// `cuts`: the cells' faces (any); the kernel's ends and centre are added to them.
void split_kernel(bool trilinear, std::vector<float>& cuts, std::vector<KernelPart>& parts) {
  const float r = trilinear ? 1.f : 0.5f;
  std::erase_if(cuts, [&](float f) { return !(f > -r && f < r); });
  cuts.insert(cuts.end(), {-r, 0.f, r});
  std::sort(cuts.begin(), cuts.end());
  parts.clear();
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1];
    if (!(b > a)) continue;
    // ∫ φ and ∫ u φ over [a, b], on one side of the centre: φ = 1 ∓ u for the tent.
    const double side = a < 0.0 ? 1.0 : -1.0;
    const double mass = trilinear ? (b - a) + side * (b * b - a * a) / 2 : (b - a) / (2.0 * r);
    const double moment =
        trilinear ? (b * b - a * a) / 2 + side * (b * b * b - a * a * a) / 3 : (b * b - a * a) / (4.0 * r);
    if (mass > 0.0) parts.push_back({float(mass), float(moment / mass), float(0.5 * (b - a))});
  }
}

// The amount of pigment k, held in a grid, for the cells of `grid` (Measure::amount),
// ∫ c dV over the medium: every voxel's value times its volume, split by its
// interpolation kernel over the cells its support reaches (exactly, per axis,
// for a grid whose axes are the world's), so each cell gets the integral of the
// interpolated c the photons' tallies read: a cell with a sliver of a voxel's
// fringe must get that sliver, or its tallies are divided by too little. Where the
// lines (`volume`, Measure::volume) found a cell only partly in the medium, a part
// counts only if its centroid is in the medium: a spill's bottom voxels are centred
// on the floor, half their tent under it, where no photon goes (counting them
// whole read 6 % too bright). A rotated grid's voxels are split into their octants instead.
// The parts are listed once (normalize() adds them twice, and finding them walks every
// voxel and casts rays in the partly filled cells): each is `amount` spread over x ± half.
struct PigmentPart {
  Vec3 x;
  float amount;
  Vec3 half;
};
std::vector<PigmentPart> pigment_parts(const Scene& scene, int medium, int k, const ExcitationGrid& volume,
                                       const ExcitationGrid& grid) {
  std::vector<PigmentPart> out;
  const Medium& m = scene.media[size_t(medium)];
  const Field& field = m.desc().pigments[size_t(k)].concentration;
  const VoxelGrid& voxels = *field.grid;
  const Transform& world = voxels.world_from_index();
  const std::array<Vec3, 3> axis{world.vector({1.f, 0.f, 0.f}), world.vector({0.f, 1.f, 0.f}),
                                 world.vector({0.f, 0.f, 1.f})};
  const float voxel_volume = std::abs(dot(axis[0], cross(axis[1], axis[2])));
  bool aligned = true;
  for (int a = 0; a < 3; ++a)
    for (int w = 0; w < 3; ++w) aligned = aligned && (a == w) == (axis[size_t(a)][w] != 0.f);
  const Vec3 reach = abs(axis[0]) + abs(axis[1]) + abs(axis[2]);  // world half-extent of an index half-width of 1
  const bool trilinear = m.desc().interpolation == Interpolation::trilinear;
  const float support = support_radius(m.desc().interpolation);
  // A uniform box with the kernel's variance per axis: tent 1/6 voxel², box 1/12.
  const Vec3 spread = reach * (trilinear ? std::sqrt(0.5f) : 0.5f);
  const double full_cell = 0.99 * grid.cell_volume();
  auto add_part = [&](const Vec3& x, float amount, const Vec3& half) {
    if (!grid.region().contains(x)) return;
    if (volume.medium_measure(grid.cell_of(x)) < full_cell && medium_at(scene, x) != medium) return;
    out.push_back({x, amount, half});
  };
  const Vec3 diagonal{axis[0].x, axis[1].y, axis[2].z};  // an aligned grid's voxel edges (signed)
  const Bounds3& region = grid.region();
  const Vec3 cell_size = grid.cell_bounds(0).diagonal();
  std::array<std::vector<KernelPart>, 3> parts;
  std::vector<float> faces;
  constexpr int kBlock = 32;
  std::vector<float> block(size_t(kBlock) * kBlock * kBlock);
  const Coord lo = voxels.index_lo(), hi = voxels.index_hi();
  for (int bz = lo[2]; bz <= hi[2]; bz += kBlock)
    for (int by = lo[1]; by <= hi[1]; by += kBlock)
      for (int bx = lo[0]; bx <= hi[0]; bx += kBlock) {
        const Coord b_lo{bx, by, bz}, b_hi{std::min(bx + kBlock - 1, hi[0]), std::min(by + kBlock - 1, hi[1]),
                                           std::min(bz + kBlock - 1, hi[2])};
        voxels.copy_block(b_lo, b_hi, block.data());
        const float* value = block.data();
        for (int z = b_lo[2]; z <= b_hi[2]; ++z)
          for (int y = b_lo[1]; y <= b_hi[1]; ++y)
            for (int x = b_lo[0]; x <= b_hi[0]; ++x) {
              const float amount = *value++ * field.scale * voxel_volume;
              if (!(amount > 0.f)) continue;
              const Vec3 index{float(x), float(y), float(z)};
              const Vec3 center = world.point(index);
              const size_t cell = grid.cell_of(center);
              const Bounds3 bounds = grid.cell_bounds(cell);
              if (volume.medium_measure(cell) >= full_cell && bounds.contains(center - support * reach) &&
                  bounds.contains(center + support * reach)) {
                out.push_back({center, amount, spread});
                continue;
              }
              if (!aligned) {
                const float o = trilinear ? 1.f / 3.f : 0.25f;  // the octants' centroids
                for (int octant = 0; octant < 8; ++octant)
                  add_part(world.point(index + Vec3{octant & 1 ? o : -o, octant & 2 ? o : -o, octant & 4 ? o : -o}),
                           0.125f * amount, 0.5f * spread);
                continue;
              }
              for (int a = 0; a < 3; ++a) {
                // The cells' faces within the support, in voxels from the centre.
                const float w0 = center[a] - support * reach[a], w1 = center[a] + support * reach[a];
                faces.clear();
                for (int j = int(std::floor((w0 - region.lo[a]) / cell_size[a])) + 1;
                     region.lo[a] + float(j) * cell_size[a] < w1; ++j)
                  faces.push_back((region.lo[a] + float(j) * cell_size[a] - center[a]) / diagonal[a]);
                split_kernel(trilinear, faces, parts[size_t(a)]);
              }
              for (const KernelPart& px : parts[0])
                for (const KernelPart& py : parts[1])
                  for (const KernelPart& pz : parts[2])
                    add_part(center + mul(Vec3{px.centroid, py.centroid, pz.centroid}, diagonal),
                             amount * px.share * py.share * pz.share, mul(Vec3{px.half, py.half, pz.half}, reach));
            }
      }
  return out;
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
  // A pigment held in a grid fills part of its medium: its tallies are weighted by concentration.
  const bool in_grid = scene.media[size_t(medium)].pigment_in_grid(fp.pigment);
  std::vector<ExcitationGrid> chunks(
      kChunks, ExcitationGrid(region, cells, in_grid ? ExcitationGrid::Measure::amount : ExcitationGrid::Measure::volume));
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
  ExcitationGrid grid = ExcitationGrid::sum_of_chunks(std::move(chunks));
  const uint64_t lines_seed = hash_combine(tracing.seed, hash_combine(uint64_t(medium), uint64_t(k)));
  if (in_grid) {
    ExcitationGrid volume(region, cells);
    Rng lines(lines_seed, 0);
    measure_medium_volume(scene, medium, volume, lines);
    const std::vector<PigmentPart> parts = pigment_parts(scene, medium, fp.pigment, volume, grid);
    grid.normalize(double(tracing.photons), [&](ExcitationGrid& g) {
      for (const PigmentPart& p : parts) g.add_pigment_amount(p.x, p.amount, p.half);
    });
  } else {
    grid.normalize(double(tracing.photons), [&](ExcitationGrid& g) {
      Rng lines(lines_seed, 0);
      measure_medium_volume(scene, medium, g, lines);
    });
  }
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
