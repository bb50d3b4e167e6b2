// `chlorovdb measure`: mean spectral radiance and colour of a pixel region with
// confidence intervals (analysis/measure.h explains the batch means and units).
#include <cstdio>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "analysis/measure.h"
#include "analysis/scene_variant.h"
#include "cli/commands.h"
#include "cli/scene_overrides.h"
#include "core/error.h"
#include "scene/scene_loader.h"

namespace chlorovdb::cli {

namespace {

struct MeasureArgs {
  std::filesystem::path scene;
  std::string region;
  MeasureOptions options;
  std::optional<int> wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution, fluorescence, transmittance, aovs;
  std::vector<std::string> sets;
  std::filesystem::path csv;
};

std::string pm(const Interval& i) { return fmt::format("{:.6e} ± {:.2e}", i.mean, i.half_width); }

// One region's report on stdout and, if `csv` is open, its CSV rows (`sensor` names it, or is empty for --region).
void report(const RegionMeasurement& m, const std::string& sensor, const std::string& source, const std::string& cs,
            std::ofstream* csv) {
  const PixelWindow& region = m.region;
  fmt::print("{}region {} of {}: {} spp in {} batches, {:g} % confidence intervals (Student t, {} dof)\n",
             sensor.empty() ? "" : fmt::format("sensor \"{}\": ", sensor), to_string(region), source, m.spp, m.batches,
             100 * m.confidence, m.batches - 1);
  fmt::print("radiance over {:g}-{:g} nm (total): {} W m^-2 sr^-1\n", kLambdaMin, kLambdaMax, pm(m.radiance));
  for (size_t l = 0; l < m.layers.size(); ++l) {
    fmt::print("{}: XYZ (W m^-2 sr^-1 nm^-1, Y = ybar-weighted mean spectral radiance)  X {}  Y {}  Z {}\n", m.layers[l],
               pm(m.xyz[l][0]), pm(m.xyz[l][1]), pm(m.xyz[l][2]));
    fmt::print("{}: RGB ({}, W m^-2 sr^-1 nm^-1)  R {}  G {}  B {}\n", m.layers[l], cs, pm(m.rgb[l][0]), pm(m.rgb[l][1]),
               pm(m.rgb[l][2]));
  }
  fmt::print("spectral radiance (total), W m^-2 sr^-1 nm^-1, {:g} nm bands:\n", m.band_width_nm);
  for (size_t b = 0; b < m.spectral.size(); ++b) fmt::print("  {:7.2f} nm  {}\n", m.band_centre_nm[b], pm(m.spectral[b]));
  if (!csv) return;
  std::ofstream& f = *csv;
  const std::string tail = fmt::format("{},{},{},\"{}\",{}", m.confidence, m.spp, m.batches, to_string(region), sensor);
  const char* names[] = {"X", "Y", "Z", "R", "G", "B"};
  f << fmt::format("radiance,total,,,W/(m2 sr),{:.9e},{:.9e},{}\n", m.radiance.mean, m.radiance.half_width, tail);
  for (size_t l = 0; l < m.layers.size(); ++l)
    for (int c = 0; c < 3; ++c) {
      f << fmt::format("xyz,{},{},,W/(m2 sr nm),{:.9e},{:.9e},{}\n", m.layers[l], names[c], m.xyz[l][c].mean, m.xyz[l][c].half_width, tail);
      f << fmt::format("rgb,{},{},,W/(m2 sr nm),{:.9e},{:.9e},{}\n", m.layers[l], names[3 + c], m.rgb[l][c].mean,
                       m.rgb[l][c].half_width, tail);
    }
  for (size_t b = 0; b < m.spectral.size(); ++b)
    f << fmt::format("spectral_radiance,total,,{:.3f},W/(m2 sr nm),{:.9e},{:.9e},{}\n", m.band_centre_nm[b], m.spectral[b].mean,
                     m.spectral[b].half_width, tail);
}

int measure(const MeasureArgs& a) {
  const SceneOverrides o = scene_overrides(a);
  const Scene scene = load_scene(a.scene, o, a.sets);
  // --region, else every sensor of the scene by name.
  std::vector<std::pair<std::string, PixelWindow>> regions;
  if (!a.region.empty()) regions.emplace_back("", parse_crop(a.region, scene.settings.width, scene.settings.height, "--region"));
  else
    for (const Sensor& s : scene.sensors) regions.emplace_back(s.name, PixelWindow{s.x0, s.y0, s.x1, s.y1});
  if (regions.empty())
    throw InputError(a.scene.string(), "sensors", "", "the scene has no sensors: give --region x0,y0,x1,y1 or a \"sensors\" key");
  MeasureOptions mo = a.options;
  mo.seed = scene.settings.seed;
  const std::string cs = scene.settings.color_space == ColorSpace::sRGB ? "linear sRGB" : "ACEScg";
  std::optional<std::ofstream> csv;
  if (!a.csv.empty()) {
    csv.emplace(a.csv);
    *csv << "quantity,layer,channel,wavelength_nm,unit,mean,half_width,confidence,spp,batches,region,sensor\n";
  }
  for (const auto& [name, region] : regions)
    report(measure_region(scene, region, mo), name, a.scene.string(), cs, csv ? &*csv : nullptr);
  if (csv) {
    csv->flush();
    if (!*csv) throw InputError(a.csv.string(), "", "", "cannot be written");
    fmt::print(stderr, "wrote {}\n", a.csv.string());
  }
  return 0;
}

}  // namespace

Command add_measure_command(CLI::App& app) {
  auto args = std::make_shared<MeasureArgs>();
  MeasureArgs& r = *args;
  CLI::App* sub = app.add_subcommand("measure", "Mean radiance (spectral, XYZ, RGB) of a pixel region with confidence intervals");
  sub->add_option("scene", r.scene, "Scene file")->required()->check(RegularFile);
  sub->add_option("--region", r.region, "Pixels x0,y0,x1,y1 (x1, y1 exclusive); default: every sensor of the scene's \"sensors\" key");
  sub->add_option("--spp", r.options.spp, "Samples per pixel (rounded up to a multiple of --batches; default 256)")
      ->check(Integer(2, kMaxSpp));
  sub->add_option("--batches", r.options.batches, "Independent batches for the interval (default 16)")->check(Integer(2, 4096));
  sub->add_option("--bands", r.options.bands, "Spectral bands over 360-830 nm (default 47: 10 nm)")->check(Integer(1, 4700));
  sub->add_option("--confidence", r.options.confidence, "Confidence level of the intervals (default 0.95)")
      ->check(Real(0.5, 0.999999));
  sub->add_option("--threads", r.options.threads, "Worker threads (default: all cores)")->check(Integer(1, kMaxThreads));
  add_scene_options(sub, r);
  sub->add_option("--csv", r.csv, "Also write every value as CSV");
  return {sub, [args] { return measure(*args); }};
}

}  // namespace chlorovdb::cli
