#include "integrator/fluorescence_event.h"

#include <algorithm>
#include <cmath>

#include "core/sampling.h"
#include "integrator/bounce_connection.h"
#include "integrator/excitation_connection.h"

namespace chlorovdb {

namespace {

constexpr int kMaxContinuationDepth = 8;
// The continuation's λ'' mixture: the lights' excitation tables, the
// reabsorption tables (emission·ε: re-emitted light), and a uniform share over
// 250–830 nm so the pdf is positive wherever any light can be absorbed.
constexpr float kUniformWavelengthShare = 0.05f;
constexpr float kReabsorptionWavelengthShare = 0.2f;
struct ContinuationShares {
  float light, reabsorption, uniform;
};
ContinuationShares continuation_shares(const FluorescentPigment& fp) {
  const float reabsorption = fp.reabsorption.empty() ? 0.f : kReabsorptionWavelengthShare;
  const float light = fp.lights.empty() ? 0.f : 1.f - kUniformWavelengthShare - reabsorption;
  return {light, reabsorption, 1.f - light - reabsorption};
}

// Where on the segment to evaluate the source: a mixture of uniform (excitation
// may peak anywhere) and exponential at the attenuation of the emitted light
// (the camera sees mostly the first optical depth). Any positive pdf is unbiased.
struct DistanceSample {
  float t, pdf;
};

DistanceSample sample_source_distance(float u, float t_end, float sigma_ref) {
  const bool use_exponential = sigma_ref * t_end > 1e-3f;
  const float norm = use_exponential ? -std::expm1(-sigma_ref * t_end) : 1.f;
  float t;
  if (!use_exponential || u < 0.5f) {
    t = (use_exponential ? u * 2.f : u) * t_end;
  } else {
    const float v = (u - 0.5f) * 2.f;
    t = std::min(t_end, -std::log1p(-v * norm) / sigma_ref);
  }
  float pdf = 1.f / t_end;
  if (use_exponential) pdf = 0.5f * pdf + 0.5f * sigma_ref * std::exp(-sigma_ref * t) / norm;
  return {t, pdf};
}

// In a grid medium the same mixture, each part weighted per majorant segment
// by the bound on the pigment's concentration there: p(t) ∝ c_max(segment) ×
// (uniform or exponential), so no point is drawn where the grid says the
// pigment cannot be (a thin shell in a large box: the leaf), and none is
// missed, since the source j ∝ c vanishes wherever c_max does. Two passes over
// the segments (totals, then the chosen one) keep it free of allocation.
// Returns pdf = 0 when the pigment is absent from the whole segment.
DistanceSample sample_source_distance_in_grid(float u, const Medium& m, int pigment, const Ray& ray, float t_end,
                                              float sigma_ref) {
  const Ray ray_index = m.index_ray(ray);
  double w_uniform = 0, w_exponential = 0;
  // Per segment: c ∫ dt (uniform part) and c ∫ sigma e^{-sigma t} dt (exponential part).
  auto exp_mass = [&](float a, float b) { return std::exp(-double(sigma_ref) * a) - std::exp(-double(sigma_ref) * b); };
  for (MajorantIterator it = m.majorants(ray_index, t_end); const auto seg = it.next();) {
    const double c = m.pigment_concentration_max(*seg, pigment);
    w_uniform += c * (seg->t_max - seg->t_min);
    w_exponential += c * exp_mass(seg->t_min, seg->t_max);
  }
  if (!(w_uniform > 0)) return {0.f, 0.f};
  const bool use_exponential = sigma_ref * t_end > 1e-3f && w_exponential > 0;
  const bool pick_uniform = !use_exponential || u < 0.5f;
  const double v = use_exponential ? (pick_uniform ? u * 2.f : (u - 0.5f) * 2.f) : u;
  double target = v * (pick_uniform ? w_uniform : w_exponential);
  float t = t_end, c_at = 0.f;
  for (MajorantIterator it = m.majorants(ray_index, t_end); const auto seg = it.next();) {
    const double c = m.pigment_concentration_max(*seg, pigment);
    if (!(c > 0)) continue;
    const double w = c * (pick_uniform ? seg->t_max - seg->t_min : exp_mass(seg->t_min, seg->t_max));
    c_at = float(c);
    if (target < w) {
      const double r = target / c;
      t = pick_uniform ? float(seg->t_min + r)
                       : float(-std::log(std::exp(-double(sigma_ref) * seg->t_min) - r) / sigma_ref);
      t = std::clamp(t, seg->t_min, seg->t_max);
      break;
    }
    target -= w;
    t = seg->t_max;  // rounding ran past the last segment: its end
  }
  double pdf = c_at / w_uniform;
  if (use_exponential) pdf = 0.5 * pdf + 0.5 * c_at * sigma_ref * std::exp(-double(sigma_ref) * t) / w_exponential;
  return {t, float(pdf)};
}

// Distance to leave the scene's bounding box (for unbounded media).
float distance_to_scene_exit(const Scene& scene, const Ray& ray) {
  float t0, t1;
  return intersect_bounds(scene.geometry.bounds(), ray, kInfinity, &t0, &t1) ? t1 : 0.f;
}

// Fluence-weighted absorption  λ'·μ_a(x,λ')·Φ̂(x,λ')  from light sources only:
// one light, one point on it, λ' ∝ S·ε·λ', the excitation ray at λ'.
// `origin`: the event, for sharing the paths through glass with its continuation.
float direct_excitation(const Scene& scene, const ContinuationOrigin& origin, float c, Rng& rng, PathStats& stats,
                        float* lambda_excitation) {
  const FluorescentPigment& fp = *origin.fp;
  const Vec3& x = origin.x;
  const int medium = origin.medium;
  if (fp.lights.empty()) return 0.f;
  const auto pick = fp.light_sampler.sample(rng.uniform());
  if (!pick) return 0.f;
  const int slot = fp.slot_of_light(pick->index);
  const ExcitationSampler& es = fp.excitation[slot];
  float pdf_lambda;
  const float lp = sample_excitation(es, rng.uniform(), &pdf_lambda);
  *lambda_excitation = lp;
  SampledWavelengths wl = SampledWavelengths::single(lp);
  const Point2 u_light{rng.uniform(), rng.uniform()};
  if (scene.settings.excitation_through_glass == ExcitationThroughGlass::connect) {
    PreparedMedia media(scene, wl);
    if (const auto fluence = connect_through_dielectrics(scene, x, medium, pick->index, u_light, media, rng, &origin)) {
      ++stats.excitation_rays;
      return lp * kAbsorptionPerMolarExtinction * fp.epsilon(lp) * c * *fluence / (pick->pmf * pdf_lambda);
    }
  }
  const auto ls = sample_Li(scene.lights[pick->index], LightSampleContext{x, Vec3{}}, u_light, wl, scene.geometry);
  if (!ls || ls->L.is_black() || !(ls->pdf > 0.f)) return 0.f;
  ++stats.excitation_rays;
  PreparedMedia media(scene, wl);
  // Thin glass walls barely deviate a ray: cross them straight with Fresnel
  // transmission so delta lights can excite liquid inside a vessel
  // (docs/fluorescence.md). In full mode, continuation paths refract through
  // glass to area and environment lights exactly, so for those the excitation
  // ray must stop at glass or that light would be counted twice.
  const bool continuations_reach_light = scene.settings.fluorescence == FluorescenceMode::full && !ls->is_delta;
  const DielectricCrossing glass =
      scene.settings.excitation_through_glass == ExcitationThroughGlass::fresnel && !continuations_reach_light
                                       ? DielectricCrossing::straight_through_fresnel
                                       : DielectricCrossing::block;
  ConnectionOptions options;
  options.dielectrics = glass;
  const SampledSpectrum T = connect_to_light(scene, ShadowOrigin{x, medium, nullptr},
                                             LightTarget{ls->wi, ls->p_light, ls->is_infinite}, media, rng, options)
                                .T;
  if (T[0] == 0.f) return 0.f;
  const float fluence = ls->L[0] * T[0] / (ls->pdf * pick->pmf * pdf_lambda);
  return lp * kAbsorptionPerMolarExtinction * fp.epsilon(lp) * c * fluence;
}

// Same quantity for the fluence that did not come straight from a light:
// an excitation path at λ'' in a direction from the medium's continuation guide
// (uniform where it has none).
// `reemitted_share`: the part of it that came from fluorescence re-emitted on the way.
float indirect_excitation(const Scene& scene, const ContinuationOrigin& origin, float c, Rng& rng, PathStats& stats,
                          int depth, float* lambda_excitation, float* reemitted_share) {
  const FluorescentPigment& fp = *origin.fp;
  const Vec3& x = origin.x;
  const int medium = origin.medium;
  float pdf_lambda;
  const float lp = sample_continuation_wavelength(fp, rng, &pdf_lambda);
  *lambda_excitation = lp;
  const float eps = fp.epsilon(lp);
  if (eps == 0.f) return 0.f;

  ++stats.excitation_continuations;
  const ContinuationGuide* guide = scene.continuation_guide(medium);
  const float u_mix = guide ? rng.uniform() : 0.f;
  const Point2 u{rng.uniform(), rng.uniform()};
  const DirectionSample dir =
      guide ? guide->sample(x, u_mix, u) : DirectionSample{sample_uniform_sphere(u), uniform_sphere_pdf()};
  float reemitted = 0.f;
  const float radiance = continuation_radiance(scene, origin, dir.w, lp, rng, stats, depth, &reemitted);
  *reemitted_share = radiance > 0.f ? reemitted / radiance : 0.f;
  const float fluence = radiance / (dir.pdf * pdf_lambda * origin.p_continue);
  return lp * kAbsorptionPerMolarExtinction * eps * c * fluence;
}

}  // namespace

float continuation_probability(int depth, int spawned) {
  return std::ldexp(1.f, -(depth + 1)) / float((1 + spawned) * (1 + spawned));
}

float continuation_wavelength_pdf(const FluorescentPigment& fp, float lambda) {
  if (!(lambda >= kLambdaMinUV && lambda < kLambdaMax)) return 0.f;
  const ContinuationShares share = continuation_shares(fp);
  float pdf = share.uniform / (kLambdaMax - kLambdaMinUV);
  for (size_t l = 0; l < fp.lights.size(); ++l)
    pdf += share.light * fp.light_sampler.pmf(fp.lights[l]) * excitation_pdf(fp.excitation[l], lambda);
  for (size_t k = 0; k < fp.reabsorption.size(); ++k)
    pdf += share.reabsorption * fp.reabsorption_choice.pmf(int(k)) * fp.reabsorption[k].pdf(lambda);
  return pdf;
}

float sample_continuation_wavelength(const FluorescentPigment& fp, Rng& rng, float* pdf) {
  const ContinuationShares share = continuation_shares(fp);
  const float u = rng.uniform();
  float lp, pdf_unused;
  if (u < share.light) {
    const auto pick = fp.light_sampler.sample(rng.uniform());
    lp = sample_excitation(fp.excitation[fp.slot_of_light(pick->index)], rng.uniform(), &pdf_unused);
  } else if (u < share.light + share.reabsorption) {
    lp = fp.reabsorption[fp.reabsorption_choice.sample(rng.uniform())].sample(rng.uniform(), &pdf_unused);
  } else {
    lp = kLambdaMinUV + rng.uniform() * (kLambdaMax - kLambdaMinUV);
  }
  *pdf = continuation_wavelength_pdf(fp, lp);
  return lp;
}

float continuation_direction_pdf(const Scene& scene, int medium, const Vec3& x, const Vec3& w) {
  const ContinuationGuide* guide = scene.continuation_guide(medium);
  return guide ? guide->pdf(x, w) : uniform_sphere_pdf();
}

float continuation_radiance(const Scene& scene, const ContinuationOrigin& origin, const Vec3& w, float lambda, Rng& rng,
                            PathStats& stats, int depth, float* reemitted) {
  SampledWavelengths wl = SampledWavelengths::single(lambda);
  PathOptions options;
  options.skip_emitters_on_first_segment = true;
  options.fluorescence_depth = depth + 1;
  options.continuation_origin = &origin;
  const PathRadiance sub = trace_path_from(scene, Ray{origin.x, w}, origin.medium, wl, rng, stats, options);
  if (reemitted) *reemitted = sub.fluorescence[0];
  return sub.fluorescence[0] + sub.other[0];
}

SampledSpectrum estimate_fluorescence_along(const Scene& scene, const Ray& ray, float t_end, int medium,
                                            PreparedMedia& media, Rng& rng, PathStats& stats, int depth,
                                            int* continuations,
                                            std::array<SampledSpectrum, kExcitationRoutes>* routes) {
  const auto& pigments = scene.fluorescence[medium];
  const SampledWavelengths& lambda = media.lambda();
  const int n = lambda.count();
  // One pigment per event, uniformly: media rarely hold more than one fluorophore.
  const int k = std::min(int(rng.uniform() * pigments.size()), int(pigments.size()) - 1);
  const FluorescentPigment& fp = pigments[k];
  const float p_pigment = 1.f / float(pigments.size());

  // Skip when no carried wavelength lies in the emission band.
  const SampledSpectrum f = fp.emission.sample(lambda);
  if (f.is_black() && scene.settings.skip_unneeded_work) return {};

  // Q as a roulette (render.quantum_yield_mode): the event is fluorescence with
  // probability Q and then weighs 1, else it contributes nothing and costs
  // nothing more. Drawn before any other work of the event, so what it saves is
  // the point, the transmittance and the excitation rays. Q = 0 never passes
  // (uniform() < 0 is false), Q = 1 always does (uniform() < 1).
  const bool q_roulette = scene.settings.quantum_yield_mode == QuantumYieldMode::roulette;
  if (q_roulette && !(rng.uniform() < fp.quantum_yield)) return {};
  const float q_weight = q_roulette ? 1.f : fp.quantum_yield;

  if (!std::isfinite(t_end) || t_end >= kInfinity) t_end = distance_to_scene_exit(scene, ray);
  if (!(t_end > 0.f)) return {};

  const Medium& m = scene.media[medium];
  const MediumProperties mid = sample_point(m, ray.at(0.5f * t_end), media[medium]);
  float sigma_ref = 0.f;
  int emitting = 0;
  for (int i = 0; i < n; ++i)
    if (f[i] > 0.f) sigma_ref += mid.sigma_a[i] + mid.sigma_s[i], ++emitting;
  sigma_ref /= float(std::max(emitting, 1));

  const DistanceSample ds = m.pigment_in_grid(fp.pigment)
                               ? sample_source_distance_in_grid(rng.uniform(), m, fp.pigment, ray, t_end, sigma_ref)
                               : sample_source_distance(rng.uniform(), t_end, sigma_ref);
  if (!(ds.pdf > 0.f)) return {};
  ++stats.fluorescence_points;
  const Vec3 x = ray.at(ds.t);
  const MediumProperties mp = sample_point(m, x, media[medium]);
  const float c = mp.concentration[fp.pigment];
  if (!(c > 0.f)) return {};
  ++stats.fluorescence_events;

  const SampledSpectrum T = transmittance(ray, ds.t, lambda, m, media[medium], scene.transmittance_estimator(medium), rng);
  if (T.is_black()) return {};

  SampledSpectrum j;  // emission per unit absorbed "λ'·μ_a·Φ", filled per lane below
  auto add_emission = [&](float absorbed, float lp) {
    if (absorbed == 0.f) return;
    for (int i = 0; i < n; ++i)
      j[i] += q_weight * f[i] * fp.redistribution(lp, lambda[i]) * kInv4Pi / lambda[i] * absorbed;
  };
  if (scene.settings.excitation_estimate == ExcitationEstimate::photons) {
    // Every route's excitation, tallied by the lamps' photons: one lookup.
    if (const ExcitationGrid* grid = scene.excitation_grid(medium, k))
      if (const ExcitationGrid::Lookup absorbed = grid->at(x); absorbed.values)
        for (int b = 0; b < ExcitationGrid::kBins; ++b)
          add_emission(kAbsorptionPerMolarExtinction * c * absorbed.profile * absorbed.values[b], ExcitationGrid::bin_center(b));
    const SampledSpectrum estimate = T * j / (ds.pdf * p_pigment);
    if (routes) *routes = {SampledSpectrum{}, SampledSpectrum{}, SampledSpectrum{}, SampledSpectrum{}, estimate};
    return estimate;
  }
  const bool may_continue = scene.settings.fluorescence == FluorescenceMode::full && depth < kMaxContinuationDepth;
  const float p_continue = may_continue ? continuation_probability(depth, *continuations) : 0.f;
  // Light a lit diffuse surface sends in through the glass, sampled from the
  // lamp's side too (bounce_connection.h), where the continuation reaches it.
  const bool bounce = may_continue && scene.settings.excitation_bounce && fp.lights_light_surfaces &&
                      scene.settings.excitation_through_glass == ExcitationThroughGlass::connect;
  const ContinuationOrigin origin{x, medium, &fp, p_continue, bounce};
  float lp = 0.f;
  const float direct = direct_excitation(scene, origin, c, rng, stats, &lp);
  add_emission(direct, lp);
  const SampledSpectrum j_connection = j;
  if (bounce) {
    const BounceExcitation b = bounce_excitation(scene, origin, c, rng, stats);
    add_emission(b.absorbed, b.lambda);
  }
  const SampledSpectrum j_bounce = j - j_connection;
  float reemitted_share = 0.f;
  if (may_continue && rng.uniform() < p_continue) {
    ++*continuations;
    const float indirect = indirect_excitation(scene, origin, c, rng, stats, depth, &lp, &reemitted_share);
    add_emission(indirect, lp);
  }

  if (routes) {
    const SampledSpectrum to_estimate = T / (ds.pdf * p_pigment);
    const SampledSpectrum j_continuation = j - j_connection - j_bounce;
    *routes = {j_connection * to_estimate, j_bounce * to_estimate,
               j_continuation * (1.f - reemitted_share) * to_estimate, j_continuation * reemitted_share * to_estimate,
               SampledSpectrum{}};
  }
  return T * j / (ds.pdf * p_pigment);
}

SampledSpectrum reference_fluorescence_event(const Scene& scene, const Vec3& p, int medium, const SampledSpectrum& beta,
                                             const SampledWavelengths& lambda, Rng& rng, PathStats& stats) {
  const auto& pigments = scene.fluorescence[medium];
  if (pigments.empty() || scene.lights.empty()) return {};
  const FluorescentPigment& fp = pigments[0];
  // Emission is triggered by absorption at the hero wavelength, inside the emission domain only.
  if (fp.emission(lambda[0]) == 0.f) return {};
  if (rng.uniform() >= fp.quantum_yield) return {};  // Q as a roulette
  ++stats.fluorescence_events;
  // "A randomly selected light source" (thesis Ch. 4): uniform over all lights.
  const int n_lights = int(scene.lights.size());
  const int pick = std::min(int(rng.uniform() * n_lights), n_lights - 1);
  const float pick_pmf = 1.f / float(n_lights);
  const Light& light = scene.lights[pick];
  const Spectrum& S = emission_spectrum(light);
  const float lo = std::max(S.support_min(), kLambdaMinUV), hi = std::min(S.support_max(), lambda[0]);
  if (!(hi > lo)) return {};
  const float le = lo + rng.uniform() * (hi - lo);  // uniform excitation wavelength
  SampledWavelengths wl = SampledWavelengths::single(le);
  const auto ls =
      sample_Li(light, LightSampleContext{p, Vec3{}}, Point2{rng.uniform(), rng.uniform()}, wl, scene.geometry);
  if (!ls || ls->L.is_black() || !(ls->pdf > 0.f)) return {};
  ++stats.excitation_rays;
  // One free-path test toward the light: a 0/1 transmittance estimate. "An opaque
  // surface" stops it (thesis Ch. 4); glass does not, or a solution in a glass would
  // never fluoresce, unlike the thesis's own images: it crosses straight with
  // Fresnel transmission, unless render.excitation_through_glass is "block" (the
  // thesis's estimator has no refracted connection).
  PreparedMedia media(scene, wl);
  const DielectricCrossing glass = scene.settings.excitation_through_glass == ExcitationThroughGlass::block
                                       ? DielectricCrossing::block
                                       : DielectricCrossing::straight_through_fresnel;
  ConnectionOptions options;
  options.dielectrics = glass;
  options.forced = TransmittanceEstimator::delta;
  const SampledSpectrum T = connect_to_light(scene, ShadowOrigin{p, medium, nullptr},
                                             LightTarget{ls->wi, ls->p_light, ls->is_infinite}, media, rng, options)
                                .T;
  if (T[0] == 0.f) return {};
  const SampledSpectrum f = fp.emission.sample(lambda);
  return beta * f * (ls->L[0] * T[0] / (ls->pdf * pick_pmf));
}

}  // namespace chlorovdb
