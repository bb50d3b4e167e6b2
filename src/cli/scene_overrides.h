#pragma once
// The scene overrides that render, reference, converge and measure take from
// the same options (--seed, --wavelengths, --fluorescence, --transmittance,
// --resolution): one place turns them into SceneOverrides.
#include "analysis/scene_variant.h"
#include "scene/scene_loader.h"

namespace chlorovdb::cli {

template <class Args>
SceneOverrides scene_overrides(const Args& a) {
  SceneOverrides o;
  o.seed = a.seed;
  o.wavelengths = a.wavelengths;
  o.fluorescence = a.fluorescence;
  o.transmittance = a.transmittance;
  if (a.resolution) parse_resolution(*a.resolution, o);
  return o;
}

}  // namespace chlorovdb::cli
