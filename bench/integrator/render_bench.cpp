// Camera paths per second on whole scenes, and what each skip saves: every
// skip is measured against the same scene with render.skip_unneeded_work off,
// in one run, so the ratios compare like with like. Time only: in this small
// slab the pairs differ by under 4 % (session 7), since the skipped work is
// cheap here and what the skips mostly save is noise (light samples spent on
// lamps that cannot excite, lanes a hero-wavelength absorption would kill):
// that shows as efficiency in docs/benchmarks.md (the skips=off rows). A pigment
// with Q = 0 has no pair: it is never fluorescent (scene/medium_param.cpp), whatever
// skip_unneeded_work says, so there is nothing to switch.
//   build/bench/integrator/bench_integrator --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>

#include "integrator/render.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

std::filesystem::path write(const std::string& name, const std::string& json) {
  const auto path = std::filesystem::temp_directory_path() / ("chlorovdb_bench_" + name + ".json");
  std::ofstream(path) << json;
  return path;
}

void render_paths(benchmark::State& state, const Scene& scene, int threads) {
  uint64_t paths = 0;
  int64_t seed = 0;
  for (auto _ : state) {
    Film film(scene.settings.width, scene.settings.height, film_layer_names(), ColorSpace::sRGB);
    RenderOptions o;
    o.spp = 1;
    o.threads = threads;
    o.seed = uint64_t(seed++);
    paths += render(scene, film, o).paths.paths;
  }
  state.counters["paths/s"] = benchmark::Counter(double(paths), benchmark::Counter::kIsRate);
}

void BM_DefaultScene(benchmark::State& state) {
  SceneOverrides o;
  o.width = 160;
  o.height = 120;
  static const Scene scene = load_scene(std::filesystem::path(CHLOROVDB_SOURCE_DIR) / "scenes/default.json", o);
  render_paths(state, scene, int(state.range(0)));
}
BENCHMARK(BM_DefaultScene)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

// A 1 cm chlorophyll slab seen through, lit by a lamp; `variant` picks what the
// skip should remove.
std::string skip_scene(const std::string& variant, bool skip) {
  const std::string solvent = variant == "absorbing" ? R"({"rayleigh": false})" : R"("water")";
  // "dark_lights": three red lamps (beyond chlorophyll's 700 nm table end) and one UV lamp.
  std::string lights = R"({"type": "point", "position": [0, 0.3, 1], "spectrum": "UVB", "scale": 50})";
  if (variant == "dark_lights")
    for (int i = 0; i < 3; ++i)
      lights += R"(, {"type": "point", "position": [)" + std::to_string(i - 1) +
                R"(, 1, 1], "spectrum": {"gaussian": [760, 10]}, "scale": 5})";
  return std::string(R"({
    "render": {"resolution": [64, 64], "wavelengths": 8, "fluorescence": "direct", "skip_unneeded_work": )") +
         (skip ? "true" : "false") + R"(},
    "camera": {"position": [0, 0, 1], "look_at": [0, 0, 0], "fov": 30},
    "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
    "materials": {"boundary": {"type": "interface"}, "floor": {"type": "diffuse", "albedo": 0.5}},
    "media": {"solution": {"solvent": )" + solvent + R"(,
              "pigments": [{"pigment": "chl", "concentration": 5, "unit": "uM"}]}},
    "shapes": [{"type": "box", "min": [-1, -1, -0.01], "max": [1, 1, 0], "material": "boundary", "inside": "solution"},
               {"type": "quad", "corner": [-2, -2, -0.2], "edge_u": [4, 0, 0], "edge_v": [0, 4, 0], "material": "floor"}],
    "lights": [)" + lights + "]}";
}

void BM_Skip(benchmark::State& state, const std::string& variant, bool skip) {
  const Scene scene = load_scene(write(variant + (skip ? "_on" : "_off"), skip_scene(variant, skip)));
  render_paths(state, scene, 1);
}
// Process CPU time (the render's worker thread, not the benchmark's own): unlike wall
// time it does not count other programs on the machine, so the on/off ratios hold
// while a build runs beside them.
#define SKIP_PAIR(name)                                                                                  \
  BENCHMARK_CAPTURE(BM_Skip, name##_skip_on, std::string(#name), true)                                  \
      ->Unit(benchmark::kMillisecond)                                                                   \
      ->MeasureProcessCPUTime();                                                                        \
  BENCHMARK_CAPTURE(BM_Skip, name##_skip_off, std::string(#name), false)                                \
      ->Unit(benchmark::kMillisecond)                                                                   \
      ->MeasureProcessCPUTime();
SKIP_PAIR(dark_lights)    // lights that cannot excite are never picked
SKIP_PAIR(absorbing)      // nothing scatters: transmittance instead of delta tracking
SKIP_PAIR(emission_band)  // paths with no wavelength in the emission band skip the event
#undef SKIP_PAIR

}  // namespace

BENCHMARK_MAIN();
