#pragma once
// sample_T_maj: delta tracking against per-wavelength majorants, the sampling
// primitive of null-scattering volumetric path tracing (pbrt-v4's SampleT_maj,
// used the same way by VolPathIntegrator::Li and for ratio-tracked shadow rays).
//
// Contract:
// - Tentative collisions are drawn with the hero wavelength's majorant
//   sigma_maj[0] (lane 0 drives distances; segments where it is 0 get none).
// - At each, callback(p, c, sigma_maj, T_maj) is called with the world-space
//   point, the medium there (MediumCollision: its coefficients on demand), the
//   segment's per-lane majorant and the per-lane majorant transmittance
//   e^{-sigma_maj dt} since the previous collision (or the ray origin), which
//   T_maj() evaluates on demand. The collision's pdf for the hero is
//   T_maj()[0] * sigma_maj[0];
//   sigma_n = sigma_maj - sigma_t >= 0.
//   The callback returns false to stop (absorption, scattering, roulette).
// - Returns the majorant transmittance from the last collision to t_max, or 1
//   if the callback stopped the walk (lanes the path does not carry are 0).
// - Distances: the ray direction need not be unit length; tracking runs in
//   metres along the normalised direction, and t_max is the ray's own parameter.
// Other lanes stay unbiased through the spectral-MIS ratios r_u, r_l the caller
// keeps (pbrt-v4): beta *= T_maj * sigma / pdf with pdf from lane 0.
#include <cmath>

#include "media/medium.h"
#include "spectra/sampled.h"
#include "tracking/majorant_walk.h"

namespace chlorovdb {

// The medium at a tentative collision, looked up once. Most collisions in thick
// media are null and need only sigma_t (and the hero's sigma_s to tell absorption
// from scattering); the full MediumProperties (per-pigment parts, phase), or the
// MediumScattering a scattering event needs, are computed only where a caller
// asks, at real collisions.
struct MediumCollision {
  const Medium& medium;
  const PreparedMedium& prepared;
  Medium::ChannelValues values;

  SampledSpectrum sigma_t() const { return medium.sigma_t(values, prepared); }
  float sigma_t(int lane) const { return medium.sigma_t(values, prepared, lane); }
  float sigma_s(int lane) const { return medium.sigma_s(values, prepared, lane); }
  MediumProperties properties() const { return medium.properties(values, prepared); }
  MediumScattering scattering() const { return medium.scattering(values, prepared); }
};

// e^{-sigma_maj dt} since the previous collision, evaluated only when asked: a
// null collision in a grey medium needs none of it (its weights are ratios of
// equal lanes), and most collisions in thick grey media are null (the cloud
// benchmark). In a grey medium only lane 0 of the optical depth is kept.
class MajorantTransmittance {
 public:
  MajorantTransmittance(const SampledSpectrum& tau_maj, int lanes, int n) : tau_maj_(tau_maj), lanes_(lanes), n_(n) {}
  SampledSpectrum operator()() const {
    if (lanes_ == n_) return detail::exp_neg_lanes(tau_maj_, 1.f, n_);
    return detail::carried_lanes(n_) * std::exp(-tau_maj_[0]);
  }

 private:
  const SampledSpectrum& tau_maj_;
  int lanes_, n_;
};

template <typename F>
SampledSpectrum sample_T_maj(Ray ray, float t_max, float u, Rng& rng, const SampledWavelengths& lambda,
                             const Medium& medium, const PreparedMedium& prepared, F callback) {
  const int n = lambda.count();
  const SampledSpectrum one = detail::carried_lanes(n);
  const float len = length(ray.d);
  if (!(len > 0.f) || !(t_max > 0.f)) return one;
  t_max *= len;
  ray.d = ray.d / len;
  const Ray ray_index = medium.index_ray(ray);
  const int channels = medium.channels();
  // A grey medium: sigma_maj and tau_maj on lane 0, broadcast where a caller reads all lanes.
  const int lanes = prepared.grey ? 1 : n;

  // Majorant optical depth since the previous collision: one exp per collision
  // at most, none per segment (cells are many where the medium is thick).
  SampledSpectrum tau_maj, sigma_maj;
  const MajorantTransmittance T_maj(tau_maj, lanes, n);
  auto add_tau = [&](float dt) {
    for (int i = 0; i < lanes; ++i) tau_maj[i] += sigma_maj[i] * dt;
  };
  float t_last = 0.f;  // previous collision, or the start of the segment
  bool broadcast = false;  // grey: sigma_maj's lane 0 still to be copied to the others
  const bool finished = detail::walk_majorants(
      medium, ray_index, t_max, u, rng,
      [&](const MajorantSegment& s) {
        for (int i = 0; i < lanes; ++i) sigma_maj[i] = prepared.sigma_t_lane(s.c_max, channels, i);
        broadcast = lanes < n;
        t_last = s.t_min;
        return sigma_maj[0];
      },
      [&](float t) {
        add_tau(t - t_last);
        t_last = t;
        if (broadcast) {  // at the segment's first collision: most segments have none
          sigma_maj = one * sigma_maj[0];  // all 16 lanes: vectorises, unlike a loop to n
          broadcast = false;
        }
        const MediumCollision c{medium, prepared, medium.channel_values(ray_index.at(t))};
        if (!callback(ray.at(t), c, sigma_maj, T_maj)) return false;
        if (lanes == 1) tau_maj[0] = 0.f;  // not a loop: gcc makes that a memset call
        else tau_maj = SampledSpectrum(0.f);
        return true;
      },
      [&](const MajorantSegment& s) { add_tau(s.t_max - t_last); });
  return finished ? T_maj() : one;
}

}  // namespace chlorovdb
