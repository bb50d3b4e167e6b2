#include "fluorescence/emission_spectrum.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace chlorovdb {

Spectrum normalise_emission(const Spectrum& s) {
  // Over the table's whole support, as Pigment validation integrates it.
  const float total = s.integral(std::min(kLambdaMinUV, s.support_min()), std::max(kLambdaMax, s.support_max()));
  if (!std::isfinite(total))
    throw std::invalid_argument(fmt::format("emission spectrum {} integrates to {} (values too large)", s.source(), total));
  if (!(total > 0.f)) throw std::invalid_argument("emission spectrum integrates to zero");
  return s.scaled(1.f / total);
}

Spectrum mirror_image_emission(const Spectrum& epsilon, const MirrorImageBand& band) {
  const auto* table = std::get_if<Spectrum::Tabulated>(&epsilon.representation());
  if (!table) throw std::invalid_argument("mirror-image rule needs a tabulated absorption spectrum");
  // Walk ε's samples in the band from red to blue so the mirrored wavelengths increase.
  std::vector<float> lambda, value;
  for (size_t i = table->lambda.size(); i-- > 0;) {
    const float la = table->lambda[i];
    if (la < band.band_min_nm || la > band.band_max_nm) continue;
    lambda.push_back(2.f * band.mirror_nm - la);
    value.push_back(table->value[i] * epsilon.scale());
  }
  if (lambda.size() < 2) throw std::invalid_argument("mirror-image band holds fewer than two absorption samples");
  // The band's edges fall to zero outside so the tabulated spectrum has no step.
  return normalise_emission(Spectrum::tabulated(std::move(lambda), std::move(value),
                                                "mirror image of " + epsilon.source()));
}

Spectrum gaussian_emission(float peak_nm, float sigma_nm) {
  return normalise_emission(Spectrum::gaussian(peak_nm, sigma_nm));
}

}  // namespace chlorovdb
