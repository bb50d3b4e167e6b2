#pragma once
// When a reference is converged enough to rank variants on (tools/benchmarks/run.sh).
//
// Criterion, per layer: the reference's own relMSE term v_ref (reference_rel_variance,
// mean of se_r² / (r² + eps) from its standard-error layers) is at most
// kReferenceShareTarget of the smallest own relMSE (own_rel_mse) among the variants at
// the budget they are ranked at. The reference then adds at most that share to any
// variant's measured relMSE, and own_rel_mse removes it in expectation.
//
// v_ref falls as 1/n in the reference's samples per pixel n, so a reference of n spp
// with term v_ref reaches a target t at n · v_ref / t spp. A variant's own relMSE
// measured after t_p seconds predicts the one at the full budget T as
// own(t_p) · t_p / T (relMSE ∝ 1/time for an unbiased estimator). A biased or
// heavy-tailed estimator's relMSE falls more slowly, so the prediction is lower than
// what it reaches and asks for more reference than needed, not less.
#include <limits>
#include <string>
#include <vector>

#include "analysis/image_error.h"

namespace chlorovdb {

inline constexpr double kReferenceShareTarget = 0.1;

// One variant's error on a layer at its largest effort, and the seconds it took.
struct VariantError {
  std::string label;
  LayerError error;
  double seconds = 0;
};

struct ReferenceCheck {
  double reference_rel_mse = 0;   // v_ref
  std::string best_label;         // the variant with the smallest own relMSE
  double best_own_rel_mse = 0;    // its own relMSE (at `budget` when predicted)
  double share = std::numeric_limits<double>::infinity();  // v_ref / best_own_rel_mse; infinite when that is <= 0
  bool met = false;               // share <= kReferenceShareTarget
};

// `budget` 0: the variants' own relMSE as measured; > 0: predicted at `budget` seconds
// from each variant's (seconds > 0). Throws std::invalid_argument without variants.
ReferenceCheck check_reference(double reference_rel_mse, const std::vector<VariantError>& variants, double budget);

// Samples per pixel at which a reference of `spp` spp meets the criterion (v_ref ∝ 1/spp),
// clamped to [spp, max_spp]; max_spp when the best variant's own relMSE is not positive.
int reference_spp_needed(int spp, const ReferenceCheck& check, int max_spp);

}  // namespace chlorovdb
