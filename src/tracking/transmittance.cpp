#include "tracking/transmittance.h"

#include <algorithm>

#include "core/constants.h"
#include "core/keyword.h"
#include "tracking/majorant_walk.h"
#include "tracking/roulette.h"

namespace chlorovdb {
namespace {

// The predicted roulette looks only at segments predicted to take at least this optical
// depth off every lane, ln(1 / kRouletteWeight): alone they would take an untouched
// factor (1) below the window. Thinner ones cost no exp; the window at collisions
// still catches what they leave.
constexpr float kPredictedRouletteMinTau = 1.3862944f;

float max_lane(const SampledSpectrum& s, int n) {
  float m = 0.f;
  for (int i = 0; i < n; ++i) m = std::max(m, s[i]);
  return m;
}

// What the estimators share: the ray in the medium's index space, in metres.
struct Track {
  const Medium& medium;
  const PreparedMedium& prepared;
  Ray ray_index;
  float t_end;
  bool unbounded;
  int n;  // carried wavelengths
  int channels;
};

// Lanes of T whose sigma over an unbounded, uniform stretch is positive become 0.
void cut_unbounded(const SampledSpectrum& sigma, int n, SampledSpectrum* T) {
  for (int i = 0; i < n; ++i)
    if (sigma[i] > 0.f) (*T)[i] = 0.f;
}

// Ratio tracking, and with kResidual residual ratio tracking: ratio tracking
// is the residual form with a control coefficient of zero (a template
// argument, so plain ratio tracking pays nothing for the control).
template <bool kResidual>
SampledSpectrum ratio_tracking(const Track& k, Rng& rng) {
  // T: the tracked (ratio) factor; tau_c: the control's optical depth, integrated
  // exactly (one exp at the end, none per segment).
  SampledSpectrum T = detail::carried_lanes(k.n), tau_c, sigma_c;
  float inv_rate = 0.f;
  detail::walk_majorants(
      k.medium, k.ray_index, k.t_end, rng.uniform(), rng,
      [&](const MajorantSegment& s) {
        if (k.unbounded && s.t_max >= k.t_end) {
          cut_unbounded(k.prepared.sigma_maj(s, k.channels, k.n), k.n, &T);
          return 0.f;
        }
        const float length = s.t_max - s.t_min;
        float rate = 0.f, tau_r_min = kInfinity;
        float tau_r[kMaxWavelengths];  // per carried lane: the residual optical depth the cell's mean predicts
        for (int i = 0; i < k.n; ++i) {
          const float sigma_maj = k.prepared.sigma_t_lane(s.c_max, k.channels, i);
          const float sigma_mean = k.prepared.sigma_t_lane(s.c_mean, k.channels, i);
          if constexpr (kResidual) {
            // The control part is integrated exactly; only the residual is tracked.
            sigma_c[i] = k.prepared.sigma_t_lane(s.c_min, k.channels, i);
            tau_c[i] += sigma_c[i] * length;
            rate = std::max(rate, sigma_maj - sigma_c[i]);
            tau_r[i] = (sigma_mean - sigma_c[i]) * length;
          } else {
            rate = std::max(rate, sigma_maj);
            tau_r[i] = sigma_mean * length;
          }
          tau_r_min = std::min(tau_r_min, tau_r[i]);
        }
        // The predicted roulette: the cell's mean predicts what this segment will do
        // to the tracked factor. Where it would take every lane below the window, the
        // roulette that would follow within a few collisions is played now, before
        // them: continue with probability q = predicted / window, survivors carry 1/q.
        // Unbiased for any q in (0, 1]; a wrong prediction costs variance, not
        // accuracy. In thick media most shadow rays end here without a lookup (the
        // cloud at tau~100: 75 % of shadow collisions came before the window).
        // tau_r_min is the least exponent over the lanes.
        if (tau_r_min > kPredictedRouletteMinTau) {
          float predicted = 0.f;
          for (int i = 0; i < k.n; ++i) predicted = std::max(predicted, T[i] * std::exp(-tau_r[i]));
          if (const float q = roulette_survival(predicted); q < 1.f) {
            if (!(rng.uniform() < q)) {
              T = SampledSpectrum(0.f);
              return -1.f;
            }
            T /= q;
          }
        }
        inv_rate = 1.f / rate;
        return rate;
      },
      [&](float t) {
        const Medium::ChannelValues v = k.medium.channel_values(k.ray_index.at(t));
        float T_max = 0.f;
        for (int i = 0; i < k.n; ++i) {  // rounding may push sigma_t a hair past the majorant: clamp
          const float sigma_t = k.medium.sigma_t(v, k.prepared, i);
          const float sigma_r = kResidual ? sigma_t - sigma_c[i] : sigma_t;
          T[i] *= std::max(0.f, 1.f - sigma_r * inv_rate);
          T_max = std::max(T_max, T[i]);
        }
        // Russian roulette once the tracked factor is small on every lane: in dense,
        // rough media most rays would otherwise track to the end for a weight that
        // hardly counts. Unbiased: survivors carry 1/q. The exact control factor
        // stays out of the test, so residual ratio tracking keeps its relative
        // accuracy in thick but smooth media (rouletting on T * T_c instead saved
        // only 1.5 % more instructions on the cloud at tau~100).
        if (const float q = roulette_survival(T_max); q < 1.f) {
          if (!(rng.uniform() < q)) {
            T = SampledSpectrum(0.f);
            return false;
          }
          T /= q;
        }
        return true;
      },
      [](const MajorantSegment&) {});
  if constexpr (kResidual)
    if (!T.is_black()) T *= detail::exp_neg_lanes(tau_c, 1.f, k.n);
  return T;
}

SampledSpectrum delta_tracking(const Track& k, Rng& rng) {
  SampledSpectrum T = detail::carried_lanes(k.n);
  float inv_rate = 0.f;
  const bool escaped = detail::walk_majorants(
      k.medium, k.ray_index, k.t_end, rng.uniform(), rng,
      [&](const MajorantSegment& s) {
        const SampledSpectrum sigma_maj = k.prepared.sigma_maj(s, k.channels, k.n);
        if (k.unbounded && s.t_max >= k.t_end) {
          cut_unbounded(sigma_maj, k.n, &T);
          return 0.f;
        }
        const float rate = max_lane(sigma_maj, k.n);
        inv_rate = 1.f / rate;
        return rate;
      },
      [&](float t) {
        const Medium::ChannelValues v = k.medium.channel_values(k.ray_index.at(t));
        float p_null[kMaxWavelengths], P = 0.f;
        for (int i = 0; i < k.n; ++i) {
          p_null[i] = std::max(0.f, 1.f - k.medium.sigma_t(v, k.prepared, i) * inv_rate);
          P = std::max(P, p_null[i]);
        }
        if (!(rng.uniform() < P)) return false;  // a real collision: the path is absorbed
        for (int i = 0; i < k.n; ++i) T[i] *= p_null[i] / P;
        return true;
      },
      [](const MajorantSegment&) {});
  return escaped ? T : SampledSpectrum(0.f);
}

}  // namespace

std::optional<TransmittanceEstimator> transmittance_estimator_from_string(std::string_view name) {
  TransmittanceEstimator e;
  if (!parse_keyword(name, {TransmittanceEstimator::delta, TransmittanceEstimator::ratio,
                            TransmittanceEstimator::residual_ratio, TransmittanceEstimator::closed_form},
                     &e))
    return std::nullopt;
  return e;
}

const char* to_string(TransmittanceEstimator estimator) {
  switch (estimator) {
    case TransmittanceEstimator::delta: return "delta";
    case TransmittanceEstimator::ratio: return "ratio";
    case TransmittanceEstimator::residual_ratio: return "residual_ratio";
    case TransmittanceEstimator::closed_form: return "closed_form";
  }
  return "?";
}

SampledSpectrum transmittance(const Ray& ray, float t_max, const SampledWavelengths& lambda, const Medium& medium,
                              const PreparedMedium& prepared, TransmittanceEstimator estimator, Rng& rng) {
  const int n = lambda.count();
  const float len = length(ray.d);
  if (!(len > 0.f) || !(t_max > 0.f)) return detail::carried_lanes(n);
  const bool unbounded = t_max >= kInfinity;
  if (estimator == TransmittanceEstimator::closed_form) {
    if (medium.homogeneous()) {
      SampledSpectrum T = detail::exp_neg_lanes(prepared.sigma_t_constant, t_max * len, n);
      if (unbounded) cut_unbounded(prepared.sigma_t_constant, n, &T);
      return T;
    }
    estimator = TransmittanceEstimator::residual_ratio;
  }
  // A grey medium attenuates every wavelength alike: track one lane and copy it
  // (the cloud benchmark: a shadow ray's lane arithmetic falls eightfold).
  const int lanes = prepared.grey ? 1 : n;
  const Track k{medium, prepared, medium.index_ray({ray.o, ray.d / len}), t_max * len, unbounded, lanes,
                medium.channels()};
  SampledSpectrum T;
  switch (estimator) {
    case TransmittanceEstimator::ratio: T = ratio_tracking<false>(k, rng); break;
    case TransmittanceEstimator::delta: T = delta_tracking(k, rng); break;
    default: T = ratio_tracking<true>(k, rng);
  }
  for (int i = lanes; i < n; ++i) T[i] = T[0];
  return T;
}

}  // namespace chlorovdb
