#pragma once
// Everything a render needs, built once from a scene file (scene_loader.h) and
// then read-only: safe to share between render threads.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "film/film.h"
#include "fluorescence/continuation_guide.h"
#include "fluorescence/excitation_grid.h"
#include "fluorescence/fluorescent_pigment.h"
#include "geometry/geometry_scene.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "media/medium.h"
#include "spectra/wavelength_sampling.h"
#include "tracking/transmittance.h"

namespace chlorovdb {

enum class FluorescenceMode { off, direct, full, reference };
// The scene-file keyword of a mode ("off", "direct", "full", "reference").
inline const char* to_string(FluorescenceMode m) {
  switch (m) {
    case FluorescenceMode::off: return "off";
    case FluorescenceMode::direct: return "direct";
    case FluorescenceMode::full: return "full";
    case FluorescenceMode::reference: return "reference";
  }
  return "?";
}
// The quantum yield Q of an event in `direct`/`full` mode: a factor on its
// contribution, or a roulette (fluorescence with probability Q, weight 1).
enum class QuantumYieldMode { weight, roulette };
// Excitation rays meeting smooth glass (docs/fluorescence.md):
//  connect — solve for the refracted path through up to 4 glass faces to every
//            light kind (integrator/specular_connection.h); exact with `full`
//            and area lights, delta lights miss the paths the solver misses;
//  fresnel — cross straight with Fresnel transmission (thin-wall approximation);
//  block   — stop (exact with `full`: light through glass then arrives only by
//            continuation paths, which cannot reach delta lights).
enum class ExcitationThroughGlass { connect, fresnel, block };
// Camera paths' next-event estimation toward point, spot and distant lights
// behind smooth glass (the caustic on a floor, the light a scattering liquid in
// a vessel receives):
//  connect — solve for the refracted paths, as excitation rays do;
//  block   — stop at glass (those lights then add nothing behind glass).
// Area lights behind glass are reached by BSDF-sampled paths either way.
enum class DirectLightThroughGlass { connect, block, all };
// The first direction of an excitation continuation (full mode): uniform over
// the sphere, or from the medium's guide learned before the render, mixed with
// uniform (guided; measured no better on the default scene, kept to measure:
// docs/fluorescence.md, "Guided continuations").
enum class ContinuationDirections { uniform, guided };
// Where a fluorescence event's absorbed excitation comes from:
//  rays    — excitation rays (and continuations in full mode) from the event: unbiased;
//  photons — a grid tallied before the render by photons traced from the lamps
//            (integrator/excitation_photons.h): every route at one lookup per event,
//            consistent (biased by the grid's cells and photon count). Counts
//            every route, the pigment's own re-emission included, in `direct` mode too.
enum class ExcitationEstimate { rays, photons };
// Camera wavelengths: from a mixture of the eye's importance with the scene's
// light spectra and the pigments' re-emission (scene), or from the eye's
// importance alone (visible; lamps with line spectra then make fireflies).
enum class CameraWavelengths { scene, visible };

struct RenderSettings {
  int width = 512, height = 512;
  int spp = 64;
  int max_depth = 32;
  int wavelengths = 8;
  uint64_t seed = 0;
  ColorSpace color_space = ColorSpace::sRGB;
  float exposure = 0.f;
  TransmittanceEstimator transmittance = TransmittanceEstimator::residual_ratio;
  bool transmittance_auto = true;  // closed form where homogeneous, residual ratio in grids
  FluorescenceMode fluorescence = FluorescenceMode::direct;
  bool fluorescence_auto = true;  // `auto` in the scene: direct where exact, full otherwise
  std::string fluorescence_reason;  // why auto chose what it chose (reported to the user)
  int spectral_bins = 0;
  AovMask aovs = 0;  // compositing layers (film/film.h, integrator/aov.h)
  // Skip work a scene does not need (absorbing-only media tracked by
  // transmittance, non-fluorescent pigments, lights dark in an excitation band,
  // paths carrying no emission wavelength). Off only to measure each skip.
  bool skip_unneeded_work = true;
  ExcitationThroughGlass excitation_through_glass = ExcitationThroughGlass::connect;
  DirectLightThroughGlass direct_light_through_glass = DirectLightThroughGlass::connect;
  // `full` mode with `connect`: excitation by light that lit diffuse surfaces
  // reflect from point, spot and area lights, also sampled from the light's side
  // (integrator/bounce_connection.h). Off only to measure it.
  bool excitation_bounce = true;
  ContinuationDirections continuation_directions = ContinuationDirections::uniform;
  ExcitationEstimate excitation_estimate = ExcitationEstimate::rays;
  int64_t excitation_photons = 1 << 18;  // per fluorescent pigment and medium
  int excitation_grid_cells = 32;        // along the medium's longest axis
  float excitation_photons_aimed = 0.5f;  // share of the photons aimed at the medium (the rest: the light's own density)
  CameraWavelengths camera_wavelengths = CameraWavelengths::scene;
  // Both kept to measure what the defaults buy (docs/fluorescence.md); neither
  // applies to the `reference` estimator, which always draws λ' uniformly below
  // λ and uses Q as a roulette, as the thesis does.
  // λ' of an excitation sample ∝ S·ε·λ' (importance) or uniform over the same band.
  ExcitationSampling excitation_sampling = ExcitationSampling::importance;
  QuantumYieldMode quantum_yield_mode = QuantumYieldMode::weight;
};

// How the integrator treats one medium, resolved once at load from the settings
// so that no segment recomputes it.
struct MediumPolicy {
  // Absorbing-only media need no collision sampling: transmittance is a weight.
  // Not for the reference estimator, whose fluorescence events are absorptions.
  bool track_by_transmittance = false;
  // The estimator the settings ask for here (closed form if homogeneous under `auto`).
  TransmittanceEstimator estimator = TransmittanceEstimator::residual_ratio;
};

// What a surface is made of and what lies on each side of it.
struct ShapeBinding {
  int material = -1;  // index into Scene::materials; -1: emitter-only shape
  int medium_inside = -1, medium_outside = -1;  // -1: vacuum
  int area_light = -1;  // index into Scene::lights
};

// A named pixel region of the image (pixels [x0, x1) x [y0, y1), in the scene's
// resolution after overrides): what `chlorovdb measure` reports without --region.
struct Sensor {
  std::string name;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct Scene {
  explicit Scene(Camera camera_) : camera(std::move(camera_)) {}
  std::filesystem::path file;
  RenderSettings settings;
  Camera camera;
  GeometryScene geometry;
  std::vector<ShapeBinding> shapes;  // by shape id
  std::vector<Material> materials;
  // Ids of the shapes with a smooth dielectric material: the interfaces connections
  // through glass solve for and seed toward (resolve_at_load fills it).
  std::vector<int> dielectric_shapes;
  std::vector<Light> lights;
  LightSampler light_sampler;        // camera-path NEE: visible power; uniform environments excluded
  WavelengthDistribution camera_wavelengths;  // what camera samples draw their lanes from
  std::vector<int> infinite_lights;  // environment lights, seen by rays that escape
  std::vector<Medium> media;
  std::vector<std::string> medium_names;
  std::vector<bool> medium_scatters;  // anything in it scatters (molecules or particles)
  std::vector<MediumPolicy> medium_policy;  // per medium, resolved at load (resolve_at_load)
  std::vector<std::vector<FluorescentPigment>> fluorescence;  // per medium
  // Per medium, where excitation continuations go first. Learned from the scene
  // itself, so the first render() trains them (integrator/continuation_guide_training.h)
  // and later renders reuse them; null, or an empty guide: uniform directions.
  mutable std::shared_ptr<const std::vector<ContinuationGuide>> continuation_guides;
  // Photon grids per medium and pigment (render.excitation_estimate = photons),
  // traced by the first render() (integrator/excitation_photons.h).
  mutable std::shared_ptr<const std::vector<std::vector<ExcitationGrid>>> excitation_grids;
  int camera_medium = -1;
  std::vector<Sensor> sensors;  // by name
  std::vector<std::string> warnings;  // loader's doubts about the scene (e.g. a grid's length unit); printed by render
  std::vector<std::string> notes;     // what the loader changed (e.g. a double grid converted to float); printed by render

  bool track_by_transmittance(int medium) const { return medium_policy[medium].track_by_transmittance; }
  TransmittanceEstimator transmittance_estimator(int medium) const { return medium_policy[medium].estimator; }

  // A shape whose material is a smooth dielectric (glass, a liquid's surface).
  bool is_dielectric(const ShapeBinding& b) const {
    return b.material >= 0 && std::holds_alternative<Dielectric>(materials[size_t(b.material)]);
  }

  // Fills the records resolved once at load: medium_policy from the settings,
  // media and fluorescence, dielectric_shapes from the shapes' materials (the
  // loader calls it last; call it again after changing any of them).
  void resolve_at_load() {
    dielectric_shapes.clear();
    for (size_t s = 0; s < shapes.size(); ++s)
      if (is_dielectric(shapes[s])) dielectric_shapes.push_back(int(s));
    medium_policy.assign(media.size(), MediumPolicy{});
    for (size_t m = 0; m < media.size(); ++m) {
      MediumPolicy& p = medium_policy[m];
      p.track_by_transmittance =
          settings.skip_unneeded_work && !medium_scatters[m] &&
          !(settings.fluorescence == FluorescenceMode::reference && !fluorescence[m].empty());
      if (settings.transmittance_auto) p.estimator = automatic_transmittance_estimator(media[m]);
      else if (settings.transmittance == TransmittanceEstimator::closed_form && !media[m].homogeneous())
        p.estimator = TransmittanceEstimator::residual_ratio;
      else p.estimator = settings.transmittance;
    }
  }

  const ExcitationGrid* excitation_grid(int medium, int pigment) const {
    if (!excitation_grids || medium < 0 || size_t(medium) >= excitation_grids->size()) return nullptr;
    const auto& grids = (*excitation_grids)[size_t(medium)];
    if (pigment < 0 || size_t(pigment) >= grids.size() || grids[size_t(pigment)].empty()) return nullptr;
    return &grids[size_t(pigment)];
  }
  const ContinuationGuide* continuation_guide(int medium) const {
    if (!continuation_guides || medium < 0 || size_t(medium) >= continuation_guides->size()) return nullptr;
    const ContinuationGuide& g = (*continuation_guides)[size_t(medium)];
    return g.empty() ? nullptr : &g;
  }

  bool has_fluorescence() const {
    for (const auto& f : fluorescence)
      if (!f.empty()) return true;
    return false;
  }
};

}  // namespace chlorovdb
