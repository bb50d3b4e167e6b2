// `chlorovdb converge`: one progressive render measured against a reference
// image or an analytic case at increasing effort -> CSV + log-log SVG plot.
// docs/convergence.md explains the metrics and the analytic cases.
#include <fstream>

#include <fmt/format.h>

#include "analysis/analytic_slab.h"
#include "analysis/loglog_fit.h"
#include "analysis/progressive.h"
#include "analysis/scene_variant.h"
#include "analysis/svg_plot.h"
#include "cli/commands.h"
#include "cli/scene_overrides.h"
#include "core/error.h"
#include "film/film.h"
#include "io/image.h"
#include "session/interrupt.h"

namespace chlorovdb::cli {

namespace {

struct ConvergeArgs {
  std::filesystem::path scene;
  std::filesystem::path reference;
  std::string analytic;
  std::string spp = "1,2,4,8,16,32,64";
  std::string time_budgets;
  std::string clock = "wall";
  std::optional<int> threads, wavelengths;
  std::optional<uint64_t> seed;
  std::optional<std::string> resolution, fluorescence, transmittance, aovs;
  std::vector<std::string> sets;
  std::string label;
  std::filesystem::path output;  // prefix: PREFIX.csv, PREFIX.svg
  bool save_images = false;
};

template <class T>
std::vector<T> parse_list(const std::string& text, const char* option) {
  std::vector<T> values;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(start, end - start);
    // Whole sample counts up to kMaxSpp, or finite positive seconds.
    const std::optional<double> v = std::is_integral_v<T> ? std::optional<double>() : parse_finite_double(item);
    const std::optional<int64_t> n = std::is_integral_v<T> ? parse_int64(item) : std::optional<int64_t>();
    if (std::is_integral_v<T> ? !n || *n < 1 || *n > kMaxSpp : !v || !(*v > 0) || *v > 1e9)
      throw InputError("command line", option, text,
                       std::is_integral_v<T> ? fmt::format("expected a comma-separated list of whole numbers in [1, {}]", kMaxSpp)
                                             : "expected a comma-separated list of positive numbers of seconds (at most 1e9)");
    values.push_back(std::is_integral_v<T> ? T(*n) : T(*v));
    start = end + 1;
  }
  return values;
}

int converge(const ConvergeArgs& a);

// The reference's own error (its standard-error layers) and whether it shares the variant's seed.
void report_reference(const Image& reference, const std::filesystem::path& file, uint64_t seed) {
  for (const ImageLayer& l : reference.layers) {
    if (is_stderr_layer(l.name) || l.channels.size() != 3) continue;
    const ReferenceSelfError e = reference_self_error(reference, l.name);
    if (!e.available) {
      fmt::print(stderr, "reference {}: layer {} has no standard-error layer: its own error is unknown\n", file.string(), l.name);
      continue;
    }
    fmt::print(stderr, "reference {}: layer {}: RMS standard error {:.3e} ({:.3g} % of its mean), adds {:.3e} to relMSE\n",
               file.string(), l.name, e.rms_stderr, e.mean != 0 ? 100 * e.rms_stderr / std::abs(e.mean) : 0.0, e.rel_mse);
  }
  if (const MetadataValue* v = reference.metadata.find("seed"))
    if (const auto* text = std::get_if<std::string>(v); text && *text == std::to_string(seed))
      fmt::print(stderr,
                 "warning: the reference was rendered with this run's seed {}: the estimate shares its first samples with the "
                 "reference and its error is underestimated; render the reference with another --seed (e.g. 1000003)\n",
                 seed);
}

}  // namespace

Command add_converge_command(CLI::App& app) {
  auto args = std::make_shared<ConvergeArgs>();
  ConvergeArgs& r = *args;
  CLI::App* sub = app.add_subcommand(
      "converge", "Error against a reference (or an analytic case) at increasing samples / time -> CSV + SVG");
  sub->add_option("scene", r.scene, "Scene file (not needed with --analytic)")->check(RegularFile);
  auto* ref = sub->add_option("--reference", r.reference, "Reference EXR (e.g. from `chlorovdb reference`)")
                  ->check(CLI::ExistingFile);
  auto* ana = sub->add_option("--analytic", r.analytic, "Analytic case instead of a reference: slab | slab_transmission | slab_linear");
  ref->excludes(ana);
  ana->excludes(ref);
  sub->add_option("--spp", r.spp, "Comma-separated sample counts (default 1,2,4,8,16,32,64)");
  sub->add_option("--time-budgets", r.time_budgets, "Comma-separated rendering times in seconds");
  sub->add_option("--clock", r.clock, "What time budgets and efficiency count: wall (default) | cpu (process CPU time, robust on a shared machine)")
      ->check(CLI::IsMember({"wall", "cpu"}));
  sub->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(Integer(1, kMaxThreads));
  add_scene_options(sub, r);
  sub->add_option("--label", r.label, "Name of this variant in the CSV and plot (default: the output prefix's name)");
  sub->add_flag("--save-images", r.save_images, "Also write PREFIX_sppN.exr at every point");
  sub->add_option("-o,--output", r.output, "Output prefix: writes PREFIX.csv and PREFIX.svg")->required();
  return {sub, [args] { return converge(*args); }};
}

namespace {

int converge(const ConvergeArgs& a) {
  if (a.reference.empty() && a.analytic.empty())
    throw InputError("command line", "--reference", "", "give a reference image or --analytic NAME");
  if (a.analytic.empty() && a.scene.empty()) throw InputError("command line", "scene", "", "a scene file is required");
  const SceneOverrides o = scene_overrides(a);
  const std::filesystem::path prefix = a.output;
  if (prefix.has_parent_path()) std::filesystem::create_directories(prefix.parent_path());
  const std::string label = a.label.empty() ? prefix.filename().string() : a.label;

  std::optional<SlabCase> slab;
  std::filesystem::path scene_file = a.scene;
  if (!a.analytic.empty()) {
    slab = analytic_case(a.analytic);
    if (!a.scene.empty()) fmt::print(stderr, "note: --analytic {} defines its own scene; {} is ignored\n", a.analytic, a.scene.string());
    scene_file = write_slab_scene(*slab, std::filesystem::path(prefix.string() + "_scene"));
  }
  const Scene scene = load_scene(scene_file, o, a.sets);
  const Image reference = slab ? slab_reference_image(*slab, scene) : read_exr(a.reference);
  if (reference.width != scene.settings.width || reference.height != scene.settings.height)
    throw InputError(a.reference.string(), "", fmt::format("{}x{}", reference.width, reference.height),
                     fmt::format("the reference's size differs from the render's {}x{} (use --resolution)",
                                 scene.settings.width, scene.settings.height));
  if (!slab) report_reference(reference, a.reference, scene.settings.seed);

  ConvergenceOptions co;
  co.spp = parse_list<int>(a.spp, "--spp");
  if (!a.time_budgets.empty()) co.time_budgets = parse_list<double>(a.time_budgets, "--time-budgets");
  co.clock = a.clock == "cpu" ? Clock::cpu : Clock::wall;
  co.threads = a.threads.value_or(0);
  co.seed = scene.settings.seed;
  co.stop = &interrupt_requested();
  co.keep_images = a.save_images;
  co.on_point = [&](const ConvergencePoint& p) {
    const LayerError* t = find_error(p.errors, "total");
    fmt::print(stderr, "{:>6} spp  {:8.3f} s ({:.3f} s CPU)  RMSE(total) {:.4e}  relMSE {:.4e}\n", p.spp, p.seconds, p.cpu_seconds,
               t ? t->rmse : 0.0, t ? t->rel_mse : 0.0);
  };
  const std::vector<ConvergencePoint> points = [&] {
    InterruptScope interrupts;
    return run_convergence(scene, reference, co);
  }();

  if (!points.empty())
    if (const std::string routes = describe_excitation_routes(points.back().excitation_routes); !routes.empty())
      fmt::print(stderr, "fluorescence seen, by what excited it (at {} spp): {}\n", points.back().spp, routes);
  // Warnings at the largest effort, where the reference's share of the error is largest.
  if (!points.empty())
    for (const LayerError& e : points.back().errors)
      for (const std::string& w : error_warnings(e)) fmt::print(stderr, "warning: {}\n", w);

  // CSV: one row per point and layer.
  const std::filesystem::path csv = prefix.string() + ".csv";
  {
    std::ofstream f(csv);
    f << "label,spp,wall_seconds,cpu_seconds,clock,time_budget,layer,mse,rmse,rel_mse,bias,reference_mean,"
         "bias_clamped,reference_mean_clamped,efficiency,efficiency_rel,reference_variance,reference_rel_variance,"
         "top_pixel_share,top_pixel_share_rel,dim_pixel_share_rel\n";
    for (const ConvergencePoint& p : points)
      for (const LayerError& e : p.errors) {
        const double t = p.time(co.clock);
        f << fmt::format(
            "{},{},{:.6f},{:.6f},{},{:g},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},"
            "{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}\n",
            label, p.spp, p.seconds, p.cpu_seconds, a.clock, p.time_budget, e.layer, e.mse, e.rmse, e.rel_mse, e.bias,
            e.reference_mean, e.bias_clamped, e.reference_mean_clamped, e.mse > 0 && t > 0 ? 1.0 / (e.mse * t) : 0.0,
            e.rel_mse > 0 && t > 0 ? 1.0 / (e.rel_mse * t) : 0.0, e.reference_variance, e.reference_rel_variance,
            e.top_pixel_share, e.top_pixel_share_rel, e.dim_pixel_share_rel);
      }
    if (!f) throw InputError(csv.string(), "", "", "cannot be written");
  }
  if (a.save_images)
    for (const ConvergencePoint& p : points) write_exr(prefix.string() + fmt::format("_spp{}.exr", p.spp), p.image);

  // Plot: RMSE against time and samples, relMSE against samples; one series per layer.
  std::vector<std::string> layers;
  if (!points.empty())
    for (const LayerError& e : points.front().errors) layers.push_back(e.layer);
  LogLogPanel vs_time{"RMSE against time: " + label, a.clock == "cpu" ? "render CPU time (s)" : "render time (s)", "RMSE", {}, -0.5};
  LogLogPanel vs_spp{"RMSE against samples", "samples per pixel", "RMSE", {}, -0.5};
  LogLogPanel rel{"relative MSE against samples", "samples per pixel", "relMSE", {}, -1.0, "slope -1"};
  std::vector<const ConvergencePoint*> by_spp;
  for (const ConvergencePoint& p : points) by_spp.push_back(&p);
  std::stable_sort(by_spp.begin(), by_spp.end(), [](auto* x, auto* y) { return x->spp < y->spp; });
  for (const std::string& layer : layers) {
    PlotSeries t{layer, {}, {}}, s{layer, {}, {}}, r{layer, {}, {}};
    std::vector<double> spp_x, rmse_y;
    for (const ConvergencePoint* p : by_spp) {
      const LayerError* e = find_error(p->errors, layer);
      if (!e) continue;
      t.x.push_back(p->time(co.clock));
      t.y.push_back(e->rmse);
      s.x.push_back(p->spp);
      s.y.push_back(e->rmse);
      r.x.push_back(p->spp);
      r.y.push_back(e->rel_mse);
    }
    const PowerFit fit = fit_power_law(s.x, s.y);
    if (fit.points >= 2) {
      fmt::print("{}: RMSE ~ spp^{:.3f} (fit over {} points, r² {:.3f})\n", layer, fit.exponent, fit.points, fit.r2);
      s.label += fmt::format(" (slope {:.2f})", fit.exponent);
    }
    vs_time.series.push_back(std::move(t));
    vs_spp.series.push_back(std::move(s));
    rel.series.push_back(std::move(r));
  }
  const std::filesystem::path svg = prefix.string() + ".svg";
  write_loglog_svg(svg, {vs_time, vs_spp, rel});
  fmt::print(stderr, "wrote {} and {}\n", csv.string(), svg.string());
  return interrupt_requested() ? 130 : 0;
}

}  // namespace
}  // namespace chlorovdb::cli
