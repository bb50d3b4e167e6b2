#include "analysis/reference_convergence.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace chlorovdb {

ReferenceCheck check_reference(double reference_rel_mse, const std::vector<VariantError>& variants, double budget) {
  if (variants.empty()) throw std::invalid_argument("check_reference: no variants");
  ReferenceCheck c;
  c.reference_rel_mse = reference_rel_mse;
  for (const VariantError& v : variants) {
    const double own = budget > 0 ? own_rel_mse(v.error) * v.seconds / budget : own_rel_mse(v.error);
    if (c.best_label.empty() || own < c.best_own_rel_mse) {
      c.best_label = v.label;
      c.best_own_rel_mse = own;
    }
  }
  c.share = c.best_own_rel_mse > 0 ? reference_rel_mse / c.best_own_rel_mse : std::numeric_limits<double>::infinity();
  c.met = c.share <= kReferenceShareTarget;
  return c;
}

int reference_spp_needed(int spp, const ReferenceCheck& check, int max_spp) {
  if (check.met) return spp;
  if (!std::isfinite(check.share)) return std::max(spp, max_spp);
  const double needed = std::ceil(double(spp) * check.share / kReferenceShareTarget);
  return int(std::clamp(needed, double(spp), double(std::max(spp, max_spp))));
}

}  // namespace chlorovdb
