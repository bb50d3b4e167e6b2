#pragma once
// One fixed-seed render of a scene at its own resolution, as an image of the
// film's layers (the analysis tests compare such renders with each other).
#include <cstdint>

#include "film/film.h"
#include "integrator/render.h"
#include "io/image.h"
#include "scene/scene.h"

namespace chlorovdb::test {

inline Image render_image(const Scene& scene, uint64_t seed, int spp) {
  Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
  RenderOptions o;
  o.spp = spp;
  o.seed = seed;
  render(scene, film, o);
  return film.to_image(spp);
}

}  // namespace chlorovdb::test
