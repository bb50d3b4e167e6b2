#pragma once
// The one loop every tracking estimator shares: walk a medium's majorant
// segments along a ray and draw tentative collisions in each at a rate the
// estimator picks per segment (exponential free flights). Delta tracking, ratio
// and residual ratio tracking and sample_T_maj differ only in the three
// callbacks. Everything is inlined: no virtual call or allocation per collision.
#include <optional>

#include "core/exponential.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "media/medium.h"

namespace chlorovdb::detail {

// begin(const MajorantSegment&) -> float: the collision rate in this segment (0: none;
//   negative: stop the walk here, as a roulette that ends the ray does);
// collide(float t) -> bool: a tentative collision at ray parameter t; false stops the walk;
// end(const MajorantSegment&): the segment is done (not called after collide returned false).
// u is the first uniform sample; later ones come from rng. Returns false if collide stopped the walk.
template <typename Begin, typename Collide, typename End>
bool walk_majorants(const Medium& medium, const Ray& ray_index, float t_max, float u, Rng& rng, Begin&& begin,
                    Collide&& collide, End&& end) {
  // The optical depth (at the estimator's rate) left to the next tentative collision.
  // Free flights are memoryless, so one exponential sample carries across segments
  // and a segment without a collision costs no log and no random number.
  // The first from u (the caller's sample), with logf instead of log1pf: 1 - u
  // is exact for Rng's 24-bit u, so log1pf's accuracy near u = 0 buys nothing.
  // The rest, one per collision, by the ziggurat: no log at all (core/exponential.h).
  float tau = -std::log(1.f - u);
  MajorantIterator it = medium.majorants(ray_index, t_max);
  while (const std::optional<MajorantSegment> seg = it.next()) {
    const float rate = begin(*seg);
    if (rate < 0.f) return false;
    if (rate > 0.f) {
      // A multiply per collision instead of a divide: the divide's latency lies on
      // the chain from one collision's position to the next lookup.
      const float inv_rate = 1.f / rate;
      float t = seg->t_min;
      for (;;) {
        const float t_next = t + tau * inv_rate;
        if (!(t_next < seg->t_max)) {
          tau = std::max(0.f, tau - rate * (seg->t_max - t));
          break;
        }
        t = t_next;
        if (!collide(t)) return false;
        tau = sample_standard_exponential(rng);
      }
    }
    end(*seg);
  }
  return true;
}

// 1 on the lanes a path carries, 0 on the others (sampled.h: unused lanes hold zero).
inline SampledSpectrum carried_lanes(int count) {
  SampledSpectrum r;
  for (int i = 0; i < count; ++i) r[i] = 1.f;
  return r;
}

// e^{-sigma dt} on the carried lanes, 0 on the others: exp is the costly part
// of a collision, so lanes nobody reads are skipped, and a grey sigma (every
// lane equal: grey media, or majorants of wavelength-independent scatterers)
// costs one exp instead of count (the cloud benchmark: 11 % of its time in expf).
inline SampledSpectrum exp_neg_lanes(const SampledSpectrum& sigma, float dt, int count) {
  SampledSpectrum r;
  bool grey = true;
  for (int i = 1; i < count; ++i) grey &= sigma[i] == sigma[0];
  if (grey) {
    const float e = std::exp(-sigma[0] * dt);
    for (int i = 0; i < count; ++i) r[i] = e;
    return r;
  }
  for (int i = 0; i < count; ++i) r[i] = std::exp(-sigma[i] * dt);
  return r;
}

}  // namespace chlorovdb::detail
