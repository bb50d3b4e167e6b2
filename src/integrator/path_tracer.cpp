#include "integrator/path_tracer.h"

#include <cmath>
#include <utility>

#include "core/sampling.h"
#include "integrator/bounce_connection.h"
#include "integrator/fluorescence_event.h"
#include "integrator/specular_connection.h"
#include "integrator/transport.h"
#include "tracking/sample_t_maj.h"

namespace chlorovdb {

namespace {

// A scattering vertex as seen by light sampling: where it is and how it scatters.
struct ScatterVertex {
  ShadowOrigin origin;
  Vec3 n;  // shading normal at surfaces, zero in media
};

// Next-event estimation: one light, one point on it, the shadow ray through
// media and interfaces. `scatter(wi)` returns {f·|cos|, pdf} of the vertex.
// Returns the MIS-weighted contribution without the path throughput.
// `through_glass`: delta lights connect through smooth dielectrics by solving
// for the refracted paths (specular_connection.h); no other strategy reaches
// them there. Area lights through glass come from BSDF-sampled paths, or with
// `area_through_glass` also from the same solve toward a point on the light
// (the floor's caustic of a lamp seen through a vessel): the path tracer then
// drops the BSDF-sampled paths the connection solves (solved_deterministically),
// and the shadow ray keeps the straight line where it crosses no glass (MIS
// with BSDF sampling).
// SMS's random seeds run at one in four of these connections, weighted by 4:
// every diffuse vertex pays for a seed, most find nothing, and the caustic's
// relMSE × time came out 1.3× lower than at every connection (glass ball on a
// floor under a point light; docs/fluorescence.md). They refract only: seeds
// that also reflect find the spot lights' glints off the teapot's glass on the
// sweep, at 2.6× the total layer's relMSE (teapot_50uM_D65_UVB_aim2, 512 spp).
constexpr SeedPolicy kCameraSeeds{0.25f, false};
// Area lights: the deterministic solves alone (the straight line's chain and its
// prefixes), every other path left to BSDF sampling, which reaches an area light
// by itself (the path tracer drops what the chains solve). SMS's seeds toward a light box found
// rare solutions weighted by counts up to 1024 × 4: with them the beaker's total
// layer had its worst 0.1 % of pixels hold up to 76 % of the squared error and
// 3.4× the relMSE × time; without, 15 %, and default.json's total layer gained 1.25×
// (docs/fluorescence.md). The straight line's path without glass is the shadow ray's.
constexpr SeedPolicy kCameraAreaSeeds{0.f, false, false};
// `clear_line_weight(light_index, p_light, n_light, wi)`: the share a light's
// straight path through no glass keeps (an excitation continuation weighs it
// against the bounce connection, bounce_connection.h; 1 elsewhere).
template <typename ScatterFn, typename ClearLineWeight>
SampledSpectrum sample_direct_light(const Scene& scene, const ScatterVertex& v, const SampledSpectrum& r_p,
                                    PreparedMedia& media, Rng& rng, bool through_glass, bool area_through_glass,
                                    ScatterFn&& scatter, ClearLineWeight&& clear_line_weight) {
  if (scene.light_sampler.empty()) return {};
  const auto pick = scene.light_sampler.sample(rng.uniform());
  if (!pick || pick->pmf == 0.f) return {};
  const Light& light = scene.lights[pick->index];
  const SampledWavelengths& lambda = media.lambda();
  if (through_glass && is_delta(light)) {
    SampledSpectrum sum;
    if (const auto arriving = light_through_dielectrics(scene, v.origin, pick->index, Point2{}, media, rng, kCameraSeeds))
      for (int i = 0; i < arriving->count; ++i) {
        const ArrivingLight::Path& p = arriving->paths[i];
        const float w =
            p.faces == 0 ? clear_line_weight(pick->index, light_position(light).value_or(Vec3{}), Vec3{}, p.wi) : 1.f;
        sum += scatter(p.wi).first * p.L * w;
      }
    return sum / (pick->pmf * r_p.average(lambda.count()));
  }
  SampledSpectrum through;  // area lights through glass (area_through_glass)
  if (area_through_glass && std::holds_alternative<AreaLight>(light)) {
    if (const auto arriving = light_through_dielectrics(scene, v.origin, pick->index, Point2{rng.uniform(), rng.uniform()},
                                                        media, rng, kCameraAreaSeeds))
      for (int i = 0; i < arriving->count; ++i) through += scatter(arriving->paths[i].wi).first * arriving->paths[i].L;
    through /= pick->pmf * r_p.average(lambda.count());
  }
  const auto ls = sample_Li(light, LightSampleContext{v.origin.p, v.n}, Point2{rng.uniform(), rng.uniform()}, lambda,
                            scene.geometry);
  if (!ls || ls->L.is_black() || !(ls->pdf > 0.f)) return through;
  const auto [f, scatter_pdf] = scatter(ls->wi);
  if (f.is_black()) return through;
  const float light_pdf = ls->pdf * pick->pmf;
  // A delta light has no MIS partner: a transmittance estimate alone, with the scene's estimator.
  ConnectionOptions options;
  options.mis = !ls->is_delta;
  LightConnection c =
      connect_to_light(scene, v.origin, LightTarget{ls->wi, ls->p_light, ls->is_infinite}, media, rng, options);
  if (c.blocked) return through;
  const float share = clear_line_weight(pick->index, ls->p_light, ls->n_light, ls->wi);
  if (ls->is_delta) return f * c.T * ls->L * share / (light_pdf * r_p.average(lambda.count()));
  c.r_l *= r_p * light_pdf;
  c.r_u *= r_p * scatter_pdf;
  return through + f * c.T * ls->L * share / (c.r_l + c.r_u).average(lambda.count());
}

}  // namespace

PathRadiance trace_path_from(const Scene& scene, Ray ray, int medium, SampledWavelengths& lambda, Rng& rng,
                             PathStats& stats, const PathOptions& options) {
  PathRadiance L;
  const int n = lambda.count();
  PreparedMedia media(scene, lambda);
  SampledSpectrum beta(1.f), r_u(1.f), r_l(1.f);
  for (int i = n; i < kMaxWavelengths; ++i) beta[i] = r_u[i] = r_l[i] = 0.f;
  bool specular_bounce = false;
  bool count_emitters = !options.skip_emitters_on_first_segment;
  float eta_scale = 1.f;
  int depth = 0;
  int continuations = 0;  // excitation continuations this path spawned (full mode)
  ScatterVertex prev{{ray.o, medium, nullptr}, Vec3{}};
  // Where the current segment really starts. A ray spawned off a surface begins
  // a float-error offset beyond it; the fluorescence integral must not skip that
  // sliver, where strongly absorbed (UV) excitation deposits most of its energy.
  Vec3 segment_start = ray.o;
  SurfaceHit prev_hit;  // storage for prev.origin.hit
  // Specular glass events (crossings and mirror reflections) since the walk's
  // origin while nothing else happened: the chain compared with the
  // connection's solves. The origin is the path's start (an excitation
  // continuation: the excitation connection owns even a clear straight line) or,
  // with area lights connected through glass, the last scattering vertex (its
  // shadow ray samples the clear straight line itself).
  const bool direct_through_glass =
      scene.settings.direct_light_through_glass != DirectLightThroughGlass::block && !scene.dielectric_shapes.empty();
  const bool area_through_glass =
      direct_through_glass && scene.settings.direct_light_through_glass == DirectLightThroughGlass::all;
  // The walk's origin as the connection sees it (a surface origin's hit is kept
  // in walk_hit: the connection and its seeds start off its surface).
  SurfaceHit walk_hit;
  ShadowOrigin walk_from{ray.o, medium, nullptr};
  SpecularChain walked;
  // From an excitation continuation's origin the other strategy is the
  // excitation connection: its share covers its random seeds' finds too.
  const bool shares_with_excitation_connection =
      options.continuation_origin && scene.settings.excitation_through_glass == ExcitationThroughGlass::connect;
  bool walked_only_glass = shares_with_excitation_connection;
  bool walk_from_excitation_origin = shares_with_excitation_connection;
  // A continuation's first diffuse vertex z, reached from its event through glass
  // alone, while its BSDF sample travels on: a hit on an area light there is the
  // bounce connection's path too (bounce_connection.h).
  struct BounceVertex {
    SpecularChain walked;  // the glass events from the event to z
    SurfaceHit z;
    float bsdf_pdf = 0.f;  // z's density for the sampled direction
  };
  std::optional<BounceVertex> bounce_vertex;
  const auto start_walk = [&](const ShadowOrigin& at) {
    walk_from = at;
    if (at.hit) {
      walk_hit = *at.hit;  // the vertex's hit storage is reused by the next bounce
      walk_from.hit = &walk_hit;
    }
    walked.count = 0;
    walked_only_glass = area_through_glass;
    walk_from_excitation_origin = false;
    bounce_vertex.reset();
  };
  ++stats.paths;

  // Light leaving an emitter toward the path, MIS-weighted against light sampling.
  auto add_emitted = [&](const SampledSpectrum& Le, int light_index, const SurfaceHit* hit_on_light) {
    if (Le.is_black() || !count_emitters) return;
    if (depth == 0 || specular_bounce) {
      L.other += beta * Le / r_u.average(n);
      return;
    }
    const float light_pdf = scene.light_sampler.pmf(light_index) * pdf_Li(scene.lights[light_index],
                                                                          LightSampleContext{prev.origin.p, prev.n},
                                                                          ray.d, scene.geometry, hit_on_light);
    const SampledSpectrum r_e = r_l * light_pdf;
    L.other += beta * Le / (r_u + r_e).average(n);
  };

  for (int segments = 0; segments < options.max_segments; ++segments) {
    ray.d = normalize(ray.d);
    const auto hit = scene.geometry.intersect(ray, kInfinity);
    const float t_end = hit ? hit->t : kInfinity;

    if (medium >= 0) {
      // Fluorescence: the source term j(x, λ) integrated along this segment.
      if (!scene.fluorescence[medium].empty() && scene.settings.fluorescence != FluorescenceMode::off &&
          scene.settings.fluorescence != FluorescenceMode::reference) {
        const SampledSpectrum weight = beta / r_u.average(n);
        const float gap = std::max(0.f, dot(ray.o - segment_start, ray.d));
        const bool camera_path = options.fluorescence_depth == 0;
        std::array<SampledSpectrum, kExcitationRoutes> routes{};
        L.fluorescence += weight * estimate_fluorescence_along(scene, Ray{ray.o - ray.d * gap, ray.d}, t_end + gap,
                                                               medium, media, rng, stats, options.fluorescence_depth,
                                                               &continuations, camera_path ? &routes : nullptr);
        if (camera_path) {
          std::array<double, kExcitationRoutes> weighted;
          for (size_t r = 0; r < weighted.size(); ++r) weighted[r] = double((weight * routes[r]).average(n));
          stats.excitation_routes.add_event(weighted);
        }
      }

      if (scene.track_by_transmittance(medium)) {
        // Nothing here scatters: no collision to sample, the transmittance is a
        // weight (closed form if homogeneous), and no hero-wavelength absorption
        // decision kills the other lanes. Light sampling does the same, so the
        // MIS weights stay consistent.
        beta *=
            transmittance(ray, t_end, lambda, scene.media[medium], media[medium], scene.transmittance_estimator(medium), rng);
        if (beta.is_black()) break;
      } else {
        // Delta tracking with the hero wavelength; other lanes are weighted (spectral MIS).
        bool scattered = false, terminated = false;
        const bool grey = media[medium].grey;
        float r_l_grey_nulls = 1.f;  // grey media: the product of the null collisions' r_l factors
        const SampledSpectrum T_maj = sample_T_maj(
            ray, t_end, rng.uniform(), rng, lambda, scene.media[medium], media[medium],
            [&](const Vec3& p, const MediumCollision& c, const SampledSpectrum& sigma_maj,
                const MajorantTransmittance& T_maj) {
              const float sigma_t0 = c.sigma_t(0);  // the hero decides
              const float sigma_s = c.sigma_s(0);
              // u sigma_maj against sigma_a, then sigma_t: the probabilities sigma / sigma_maj
              // without a divide per collision.
              const float u = rng.uniform() * sigma_maj[0];
              if (u < sigma_t0 - sigma_s) {
                if (scene.settings.fluorescence == FluorescenceMode::reference)
                  L.fluorescence +=
                      reference_fluorescence_event(scene, p, medium, beta / r_u.average(n), lambda, rng, stats);
                terminated = true;
                return false;
              }
              if (u < sigma_t0) {
                if (depth++ >= scene.settings.max_depth) {
                  terminated = true;
                  return false;
                }
                const MediumScattering mp = c.scattering();
                const SampledSpectrum T_m = T_maj();
                const float pdf = T_m[0] * mp.sigma_s[0];
                beta *= T_m * mp.sigma_s / pdf;
                r_u *= T_m * mp.sigma_s / pdf;
                if (beta.is_black() || r_u.is_black()) {
                  terminated = true;
                  return false;
                }
                const Vec3 wo = -ray.d;
                const ScatterVertex v{{p, medium, nullptr}, Vec3{}};
                L.other += beta * sample_direct_light(
                                      scene, v, r_u, media, rng, direct_through_glass, area_through_glass,
                                      [&](const Vec3& wi) {
                                        return std::pair{phase_eval(mp.phase, wo, wi), phase_pdf(mp.phase, wo, wi)};
                                      },
                                      [](int, const Vec3&, const Vec3&, const Vec3&) { return 1.f; });
                const MediumPhaseSample ps = phase_sample(mp.phase, wo, Point2{rng.uniform(), rng.uniform()});
                if (!(ps.pdf > 0.f)) {
                  terminated = true;
                  return false;
                }
                beta *= ps.p / ps.pdf;
                r_l = r_u / ps.pdf;
                prev = v;
                specular_bounce = false;
                count_emitters = true;
                scattered = true;
                start_walk(v.origin);
                ray = Ray{p, ps.wi};
                segment_start = p;
                return false;
              }
              // Null collision: continue, weighting every lane by sigma_n / its pdf.
              // r_u and r_l are both relative to the pdf of what was sampled
              // (T_maj[0] sigma_n[0]); r_l follows ratio tracking's sigma_maj.
              if (grey) {
                // Every lane's T_maj sigma_n is the pdf itself: beta and r_u keep
                // their values, r_l changes by one factor, applied once the walk
                // ends (most collisions in a thick grey medium are null: the cloud
                // benchmark). A scattering overwrites r_l, so it then never applies.
                const float sigma_n0 = sigma_maj[0] - sigma_t0;
                if (!(sigma_n0 > 0.f)) {
                  terminated = true;
                  return false;
                }
                r_l_grey_nulls *= sigma_maj[0] / sigma_n0;
                return true;
              }
              const SampledSpectrum T_m = T_maj();
              const SampledSpectrum sigma_n = clamp_zero(sigma_maj - c.sigma_t());
              const float pdf = T_m[0] * sigma_n[0];
              if (!(pdf > 0.f)) {
                terminated = true;
                return false;
              }
              beta *= T_m * sigma_n / pdf;
              r_u *= T_m * sigma_n / pdf;
              r_l *= T_m * sigma_maj / pdf;
              return !beta.is_black() && !r_u.is_black();
            });
        if (terminated || beta.is_black() || r_u.is_black()) break;
        if (scattered) continue;
        beta *= T_maj / T_maj[0];
        r_u *= T_maj / T_maj[0];
        r_l *= T_maj * (r_l_grey_nulls / T_maj[0]);
      }
    }

    if (!hit) {
      for (int li : scene.infinite_lights)
        add_emitted(Le_environment(std::get<EnvironmentLight>(scene.lights[li]), ray.d, lambda), li, nullptr);
      break;
    }

    const ShapeBinding& binding = scene.shapes[hit->shape_id];
    if (binding.area_light >= 0) {
      // The share of the light left to this path when a connection also solves it.
      float share = 1.f;
      if (walked_only_glass && walk_from_excitation_origin)
        share = continuation_weight_against_connection(scene, *options.continuation_origin, walked, hit->p, hit->ng,
                                                       binding.area_light, lambda[0], rng);
      else if (walked_only_glass && walked.count > 0 &&
               solved_deterministically(scene, connection_start(scene, walk_from, hit->p - walk_from.p), hit->p, walked,
                                        lambda[0]))
        share = 0.f;
      else if (bounce_vertex)
        share = continuation_weight_against_bounce(scene, *options.continuation_origin, bounce_vertex->walked,
                                                   bounce_vertex->z, binding.area_light, lambda[0],
                                                   LightVertex{hit->p, hit->ng, bounce_vertex->bsdf_pdf});
      if (share > 0.f)
        add_emitted(Le_area(std::get<AreaLight>(scene.lights[binding.area_light]), hit->ng, -ray.d, lambda) * share,
                    binding.area_light, &*hit);
    }

    if (is_pass_through(scene, binding)) {
      // A medium boundary: cross it without a bounce.
      medium = medium_after_crossing(binding, hit->ng, ray.d);
      ray = scene.geometry.spawn_ray(*hit, ray.d);
      segment_start = hit->p;
      continue;
    }
    if (depth++ >= scene.settings.max_depth) break;
    bounce_vertex.reset();

    const Vec3 wo = -ray.d;
    const Bsdf bsdf = make_bsdf(scene.materials[binding.material], *hit, lambda);
    prev_hit = *hit;
    const int medium_here = dot(wo, hit->ng) > 0.f ? binding.medium_outside : binding.medium_inside;
    const ScatterVertex v{{hit->p, medium_here, &prev_hit}, hit->ns};
    // A continuation's first diffuse vertex, reached from its event through glass
    // alone: the bounce connection samples the same paths from the light.
    const bool weigh_against_bounce =
        !bsdf.is_specular() && walk_from_excitation_origin && options.continuation_origin->bounce && walked_only_glass;
    if (!bsdf.is_specular()) {
      L.other += beta * sample_direct_light(
                            scene, v, r_u, media, rng, direct_through_glass, area_through_glass,
                            [&](const Vec3& wi) {
                              return std::pair{bsdf.f(wo, wi) * std::fabs(dot(wi, hit->ns)), bsdf.pdf(wo, wi)};
                            },
                            [&](int light_index, const Vec3& p_light, const Vec3& n_light, const Vec3& wi) {
                              return weigh_against_bounce
                                         ? continuation_weight_against_bounce(
                                               scene, *options.continuation_origin, walked, *hit, light_index,
                                               lambda[0], LightVertex{p_light, n_light, bsdf.pdf(wo, wi)})
                                         : 1.f;
                            });
    }
    const auto bs = bsdf.sample(wo, rng.uniform(), Point2{rng.uniform(), rng.uniform()});
    if (!bs || bs->pdf == 0.f) break;
    if (!bsdf.is_specular()) {
      // The walk to z is kept only where the bounce connection can share its light.
      std::optional<BounceVertex> at_z;
      if (weigh_against_bounce) at_z = BounceVertex{walked, *hit, bs->pdf};
      start_walk(v.origin);
      bounce_vertex = std::move(at_z);
    } else if (walked_only_glass) {
      const bool glass = bs->is_specular && std::holds_alternative<Dielectric>(scene.materials[binding.material]);
      if (glass && walked.count < kMaxSpecularChain)
        walked.faces[walked.count++] =
            ChainFace{hit->shape_id, hit->prim_id, hit->ng, dot(hit->ng, hit->p), hit->p, !bs->is_transmission};
      else
        walked_only_glass = false;
    }
    beta *= bs->f * std::fabs(dot(bs->wi, hit->ns)) / bs->pdf;
    r_l = r_u / bs->pdf;
    specular_bounce = bs->is_specular;
    count_emitters = true;
    if (bs->is_transmission) eta_scale *= bs->eta * bs->eta;
    prev = v;
    // Crossing a refracting surface changes medium; reflection keeps it.
    medium = dot(bs->wi, hit->ng) < 0.f ? binding.medium_inside : binding.medium_outside;
    ray = scene.geometry.spawn_ray(*hit, bs->wi);
    segment_start = hit->p;

    // Russian roulette on the MIS-weighted throughput (eta_scale undoes radiance
    // compression inside dense dielectrics).
    const SampledSpectrum rr_beta = beta * eta_scale / r_u.average(n);
    if (rr_beta.max_value() < 1.f && depth > 1) {
      const float q = std::max(0.f, 1.f - rr_beta.max_value());
      if (rng.uniform() < q) break;
      beta /= 1.f - q;
    }
  }
  return L;
}

PathRadiance trace_path(const Scene& scene, Ray ray, int medium, SampledWavelengths& lambda, Rng& rng,
                        PathStats& stats) {
  return trace_path_from(scene, ray, medium, lambda, rng, stats, PathOptions{});
}

}  // namespace chlorovdb
