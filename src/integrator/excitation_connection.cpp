#include "integrator/excitation_connection.h"

#include <cmath>

#include "core/sampling.h"
#include "integrator/fluorescence_event.h"

namespace chlorovdb {

namespace {

// Area lights: the random seed at one connection in four (weight 4). A seed
// through a mesh vessel costs a Newton solve that the straight line's planar
// film does not; under the beaker's overhead F2 panel (glass_F2_5uM, 96×72,
// 12 seeds) every connection took 1.8× the CPU time for no lower error
// (fluorescence relMSE × s 0.42× the connection without seeds, one in four
// 1.04×), while on default.json (24 seeds) both were alike and on the beaker
// under UVB (12 seeds) within 1σ (5.3× against 6.8× over `block`). Delta
// lights have no other strategy: every connection.
constexpr float kAreaLightSeedProbability = 0.25f;
// SMS's p(S) as the weights see it, for every seeded path (the header): the
// seeds' finds that dominated glass_UVB_5uM_Q0.23's error have p of a few per
// cent. 24 seeds × 512 spp, 32×24, fluorescence relMSE × CPU-s: 0.347 with
// 1/16, 0.404 with 1, 0.370 with 1/256 (0.603 before the two strategies shared
// paths, the connection owning what it could return; docs/fluorescence.md).
constexpr float kSeedFindProbability = 1.f / 16;

// The connection's density of a path (the header's formula) from the light
// point's density per solid angle at x.
float connection_path_density(const ContinuationOrigin& origin, int light_index, float lambda_nm, float pdf_solid_angle,
                              bool seeded) {
  const FluorescentPigment& fp = *origin.fp;
  const int slot = fp.slot_of_light(light_index);
  if (slot < 0) return 0.f;
  const float p_strategy = seeded ? kAreaLightSeedProbability * kSeedFindProbability : 1.f;
  return p_strategy * fp.light_sampler.pmf(light_index) * excitation_pdf(fp.excitation[size_t(slot)], lambda_nm) *
         pdf_solid_angle;
}

}  // namespace

float continuation_path_density(const Scene& scene, const ContinuationOrigin& origin, const Vec3& w0, float lambda_nm,
                                float fresnel) {
  if (!(origin.p_continue > 0.f)) return 0.f;
  return origin.p_continue * continuation_wavelength_pdf(*origin.fp, lambda_nm) *
         continuation_direction_pdf(scene, origin.medium, origin.x, w0) * fresnel;
}

std::optional<float> connect_through_dielectrics(const Scene& scene, const Vec3& x, int medium, int light_index,
                                                 Point2 u, PreparedMedia& media, Rng& rng,
                                                 const ContinuationOrigin* origin) {
  const bool area = std::holds_alternative<AreaLight>(scene.lights[light_index]);
  const SeedPolicy seeds{area ? kAreaLightSeedProbability : 1.f, true};
  const auto arriving =
      light_through_dielectrics(scene, ShadowOrigin{x, medium, nullptr}, light_index, u, media, rng, seeds);
  if (!arriving) return std::nullopt;
  const bool shared = area && origin && origin->p_continue > 0.f;
  const float lambda_nm = media.lambda()[0];
  float fluence = 0.f;
  for (int i = 0; i < arriving->count; ++i) {
    const ArrivingLight::Path& p = arriving->paths[i];
    float w = 1.f;
    if (shared && p.faces > 0)
      w = power_heuristic(1, connection_path_density(*origin, light_index, lambda_nm, p.pdf_solid_angle, p.seeded), 1,
                          continuation_path_density(scene, *origin, p.wi, lambda_nm, p.fresnel));
    fluence += w * p.L[0];
  }
  return fluence;
}

float continuation_weight_against_connection(const Scene& scene, const ContinuationOrigin& origin,
                                             const SpecularChain& walked, const Vec3& y, const Vec3& ng,
                                             int light_index, float lambda_nm, Rng& rng) {
  if (walked.count == 0 || origin.fp->slot_of_light(light_index) < 0) return 1.f;
  auto path = deterministic_solution(scene, origin.x, y, walked, lambda_nm);
  const bool seeded = !path;
  if (seeded) path = seed_reachable_solution(scene, origin.x, y, walked, lambda_nm);
  if (!path) return 1.f;
  const auto& area = std::get<AreaLight>(scene.lights[light_index]);
  const float pdf_solid_angle = float(1.0 / (scene.geometry.area(area.shape_id) * solid_angle_per_area(*path, ng)));
  const float w = power_heuristic(
      1, connection_path_density(origin, light_index, lambda_nm, pdf_solid_angle, seeded), 1,
      continuation_path_density(scene, origin, path->dir[0], lambda_nm, path_fresnel(scene, *path, lambda_nm)));
  if (!seeded) return 1.f - w;
  return seeds_miss(scene, origin.x, y, *path, lambda_nm, rng) ? 1.f : 1.f - w;
}

}  // namespace chlorovdb
