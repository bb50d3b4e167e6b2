// Loads a scene with a named spectrum and a fluorescent pigment, renders it,
// and checks the film: what a user's program linked to chlorovdb::chlorovdb does.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "spectra/library.h"

int main(int argc, char** argv) {
  using namespace chlorovdb;
  setenv("CHLOROVDB_SPECTRA", DOWNSTREAM_SPECTRA_DIR, 1);
  const std::filesystem::path dir = argc > 1 ? argv[1] : ".";
  const auto scene_file = dir / "downstream_scene.json";
  std::ofstream(scene_file) << R"({
    "render": {"resolution": [4, 3], "wavelengths": 4},
    "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]},
    "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
    "media": {"s": {"pigments": [{"pigment": "chl", "concentration": 20}]}},
    "materials": {"b": {"type": "interface"}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "b", "inside": "s"}],
    "lights": [{"type": "environment", "spectrum": "D65", "scale": 0.01}]
  })";
  try {
    const Scene scene = load_scene(scene_file);
    Film film(scene.settings.width, scene.settings.height, film_layer_names(), ColorSpace::sRGB);
    RenderOptions options;
    options.spp = 2;
    options.threads = 1;
    const RenderStats stats = render(scene, film, options);
    const Image image = film.to_image(stats.samples_done);
    double sum = 0;
    for (float v : image.layers[0].pixels) {
      if (!std::isfinite(v)) return 1;
      sum += v;
    }
    if (!(sum > 0) || film.nonfinite_samples() != 0) return 2;
    std::printf("downstream: ok (%d spp, spectra from %s, D65(560) = %g)\n", stats.samples_done,
                spectra_dir().c_str(), double(named_spectrum("D65")(560.f)));
  } catch (const InputError& e) {
    std::fprintf(stderr, "downstream: %s\n", e.what());
    return 3;
  }
  return 0;
}
