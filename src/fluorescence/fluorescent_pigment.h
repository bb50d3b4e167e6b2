#pragma once
// A fluorescent pigment as the fluorescence estimator sees it: its spectra,
// quantum yield and redistribution, and the lights that can excite it with one
// excitation-wavelength sampler per light (filled in by the scene loader, which
// knows the lights' power).
#include <vector>

#include "fluorescence/excitation_sampler.h"
#include "fluorescence/redistribution.h"
#include "lights/light_sampler.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

// One fluorescent pigment of one medium, with what excitation needs: the
// lights that can excite it (others are never picked) and, per such light, the
// λ' sampler ∝ S_light·ε·λ'; and, for reabsorption, one λ'' sampler per
// fluorescent pigment of the scene whose emission this one absorbs.
struct FluorescentPigment {
  int pigment = 0;  // index into the medium's pigments
  float quantum_yield = 0.f;
  Spectrum epsilon;   // L mol^-1 cm^-1
  Spectrum emission;  // unit integral
  RedistributionWeight redistribution;
  std::vector<int> lights;                     // lights that can excite it
  std::vector<ExcitationSampler> excitation;   // parallel to `lights`
  LightSampler light_sampler;                  // over `lights`, weighted by excitation power
  // Some of `lights` is a point, spot or area light: the floor it lights can send
  // its light in (integrator/bounce_connection.h).
  bool lights_light_surfaces = false;
  // ∝ emission_k·ε·λ'' per emitting pigment k (the light reabsorbed here is
  // fluorescence): the continuation's λ'' mixture draws from these so
  // re-emitted light is found where the emission and absorption bands overlap.
  // A table is picked with probability ∝ Q_k · its total (the overlap).
  std::vector<ExcitationSampler> reabsorption;
  Distribution1D reabsorption_choice;  // over `reabsorption`
  // Some listed light shines in the absorption band (a light kept only to
  // measure the cost of not skipping dark lights does not count).
  bool excitation_possible() const {
    for (const ExcitationSampler& es : excitation)
      if (es.can_excite()) return true;
    return false;
  }
  int slot_of_light(int light_index) const {   // position of a light in `lights`
    for (size_t s = 0; s < lights.size(); ++s)
      if (lights[s] == light_index) return int(s);
    return -1;
  }
};

}  // namespace chlorovdb
