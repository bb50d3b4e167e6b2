// chlorovdb_bench: the helper behind tools/benchmarks/run.sh (not installed).
//   plot   CSV... -o OUT.svg      RMSE against time / samples, one series per CSV label
//   table  CSV... --baseline L    markdown efficiency table (last point of each label)
//   slope  CSV... --baseline L    convergence rate over seeds (one CSV per seed; whole range and last octaves) and relMSE x time
//   reference-check CSV... --reference REF.exr   is the reference converged enough to rank the CSVs' variants?
//   cost-growth --out DIR         time per sample against optical depth and grid size
// CSVs are those of `chlorovdb converge`.
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <time.h>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "analysis/image_error.h"
#include "analysis/loglog_fit.h"
#include "analysis/reference_convergence.h"
#include "analysis/svg_plot.h"
#include "core/error.h"
#include "core/number.h"
#include "grids/vdb_file.h"
#include "integrator/render.h"
#include "io/image.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

// ---- converge CSVs -------------------------------------------------------

struct Row {
  std::string label, clock;
  int spp = 0;
  double seconds = 0, budget = 0;
  // The layer's error; columns missing in older CSVs stay 0. `bias` and
  // `reference_mean` are the clamped ones where the CSV has them.
  LayerError error;
  // Mean bias relative to the reference's mean, both images clamped at the
  // reference's 99.9th percentile (analysis/image_error.h): about 0 (within
  // noise) for an unbiased estimator; -1: the variant renders nothing of this layer.
  double relative_bias() const { return error.reference_mean != 0 ? error.bias / error.reference_mean : 0.0; }
  // Equal-time efficiencies on the estimate's own errors (the reference's term removed):
  // 0 where that is not positive (the reference's term is the whole measured error).
  double efficiency() const { return own_mse(error) > 0 && seconds > 0 ? 1.0 / (own_mse(error) * seconds) : 0.0; }
  double efficiency_rel() const { return own_rel_mse(error) > 0 && seconds > 0 ? 1.0 / (own_rel_mse(error) * seconds) : 0.0; }
};

// Columns by name (converge's header), so the CSV can grow. `seconds` is the
// time of the clock the run measured budgets in (wall or cpu).
std::vector<Row> read_rows(const std::vector<std::string>& files, const std::string& layer) {
  std::vector<Row> rows;
  auto split = [](const std::string& line) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    return c;
  };
  for (const std::string& file : files) {
    std::ifstream f(file);
    if (!f) throw InputError(file, "", "", "cannot be read");
    std::string line;
    std::getline(f, line);
    std::map<std::string, size_t> col;
    const auto header = split(line);
    for (size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
    for (const char* need : {"label", "spp", "wall_seconds", "cpu_seconds", "clock", "time_budget", "layer", "mse", "rmse",
                             "rel_mse", "bias", "reference_mean"})
      if (!col.count(need)) throw InputError(file, need, "", "missing column (not a chlorovdb converge CSV?)");
    while (std::getline(f, line)) {
      const auto c = split(line);
      if (c.size() < header.size() || c[col["layer"]] != layer) continue;
      auto number = [&](const char* name) { return col.count(name) ? std::stod(c[col[name]]) : 0.0; };
      Row r;
      r.label = c[col["label"]];
      r.clock = c[col["clock"]];
      r.spp = std::stoi(c[col["spp"]]);
      r.seconds = number(r.clock == "cpu" ? "cpu_seconds" : "wall_seconds");
      r.budget = number("time_budget");
      LayerError& e = r.error;
      e.layer = layer;
      e.mse = number("mse");
      e.rmse = number("rmse");
      e.rel_mse = number("rel_mse");
      e.bias = number("bias");
      e.reference_mean = number("reference_mean");
      if (col.count("bias_clamped")) {  // robust to a reference's fireflies
        e.bias = number("bias_clamped");
        e.reference_mean = number("reference_mean_clamped");
      }
      e.reference_variance = number("reference_variance");
      e.reference_rel_variance = number("reference_rel_variance");
      e.top_pixel_share = number("top_pixel_share");
      e.top_pixel_share_rel = number("top_pixel_share_rel");
      if (col.count("dim_pixel_share_rel")) e.dim_pixel_share_rel = number("dim_pixel_share_rel");
      rows.push_back(r);
    }
  }
  return rows;
}

// The last (largest-effort) row of each label, and the labels in order of appearance.
std::map<std::string, Row> last_rows(const std::vector<Row>& rows, std::vector<std::string>* labels = nullptr) {
  std::map<std::string, Row> last;
  for (const Row& r : rows) {
    if (!last.count(r.label) && labels) labels->push_back(r.label);
    if (!last.count(r.label) || r.seconds >= last[r.label].seconds) last[r.label] = r;
  }
  return last;
}

int plot(const std::vector<std::string>& files, const std::string& layer, const std::string& title, const std::string& out,
         const std::string& time_label) {
  const std::vector<Row> rows = read_rows(files, layer);
  std::vector<std::string> labels;
  for (const Row& r : rows)
    if (std::find(labels.begin(), labels.end(), r.label) == labels.end()) labels.push_back(r.label);
  LogLogPanel by_time{title + ": RMSE (" + layer + ") against time", time_label, "RMSE", {}, -0.5};
  LogLogPanel by_spp{"RMSE (" + layer + ") against samples", "samples per pixel", "RMSE", {}, -0.5};
  for (const std::string& label : labels) {
    PlotSeries t{label, {}, {}}, s{label, {}, {}};
    for (const Row& r : rows)
      if (r.label == label) {
        t.x.push_back(r.seconds);
        t.y.push_back(r.error.rmse);
        s.x.push_back(r.spp);
        s.y.push_back(r.error.rmse);
      }
    by_time.series.push_back(t);
    by_spp.series.push_back(s);
  }
  write_loglog_svg(out, {by_time, by_spp});
  return 0;
}

// One markdown row per label: its last (largest-effort) point. Ranked on
// 1/(own relMSE x time), own relMSE = relMSE minus the reference's own term
// (analysis/image_error.h): relMSE bounds what each pixel contributes where the
// reference itself is very bright, so a reference's few unconverged pixels
// (fireflies) cannot decide the comparison as they do MSE. A row is marked ⚠ where
// relMSE does not measure the variant (relative_error_trustworthy: the reference's
// share of it over 10 %, or the worst 0.1 % of pixels holding over 20 % of it); a
// sentence under the table names those rows.
int table(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline) {
  const std::vector<Row> rows = read_rows(files, layer);
  std::vector<std::string> labels;
  std::map<std::string, Row> last = last_rows(rows, &labels);
  const double base = last.count(baseline) ? last[baseline].efficiency_rel() : 0.0;
  const std::string clock = rows.empty() ? "wall" : rows.front().clock;
  fmt::print("| variant | spp | {} s | RMSE | relMSE | ref. share | own relMSE | worst 0.1 % px: relMSE / MSE | mean bias | 1/(MSE·s) "
             "| 1/(relMSE·s) | vs {} |\n",
             clock == "cpu" ? "CPU" : "wall", baseline);
  fmt::print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  std::vector<std::string> flagged;
  auto efficiency = [](double e) { return e > 0 ? fmt::format("{:.3e}", e) : std::string("–"); };
  for (const std::string& label : labels) {
    const Row& r = last[label];
    const LayerError& e = r.error;
    const bool trusted = relative_error_trustworthy(e);
    if (!trusted) flagged.push_back(label);
    fmt::print("| {}{} | {} | {:.2f} | {:.3e} | {:.3e} | {:.1f} % | {:.3e} | {:.1f} / {:.1f} % | {:+.1f} % | {} | {} | {} |\n", label,
               trusted ? "" : " ⚠", r.spp, r.seconds, e.rmse, e.rel_mse, 100 * reference_rel_share(e), own_rel_mse(e),
               100 * e.top_pixel_share_rel, 100 * e.top_pixel_share, 100 * r.relative_bias(), efficiency(r.efficiency()),
               efficiency(r.efficiency_rel()),
               base > 0 && r.efficiency_rel() > 0 ? fmt::format("{:.2f}×", r.efficiency_rel() / base) : "–");
  }
  if (!flagged.empty()) {
    std::string names;
    for (const std::string& l : flagged) names += (names.empty() ? "" : ", ") + l;
    fmt::print("\n⚠ Not a trustworthy ranking on this layer: {} (the reference's own term is over {:.0f} % of relMSE, or the "
               "worst {:g} % of pixels hold over {:.0f} % of it).\n",
               names, 100 * kReferenceDominatesShare, 100 * kTopPixelFraction, 100 * kTopPixelShareWarning);
  }
  return 0;
}

// "LABEL GAIN BIAS BASELINE_BIAS": the label with the highest 1/(own relMSE x time)
// (among `candidates`, all if empty), its gain over `baseline`, and both
// relative mean biases in per cent.
int best(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline,
         const std::vector<std::string>& candidates) {
  std::map<std::string, Row> last = last_rows(read_rows(files, layer));
  if (!last.count(baseline) || !(last[baseline].efficiency_rel() > 0)) throw std::runtime_error("no baseline " + baseline);
  std::string top;
  for (const auto& [label, r] : last) {
    if (!candidates.empty() && std::find(candidates.begin(), candidates.end(), label) == candidates.end()) continue;
    if (top.empty() || r.efficiency_rel() > last[top].efficiency_rel()) top = label;
  }
  fmt::print("{} {:.2f} {:+.1f} {:+.1f}\n", top, last[top].efficiency_rel() / last[baseline].efficiency_rel(),
             100 * last[top].relative_bias(), 100 * last[baseline].relative_bias());
  return 0;
}

// Whether a reference meets the criterion of analysis/reference_convergence.h
// against the variants of `files` (their last points), per layer. One line per
// layer the reference has with a non-zero mean:
//   LAYER SPP REF_REL_MSE RMS_REL_STDERR BEST_LABEL BEST_OWN_REL_MSE SHARE NEEDED_SPP MET
// SPP is the reference's spp_done; RMS_REL_STDERR its RMS standard error over its mean;
// with `budget` > 0 the variants' own relMSE is predicted at that time (a pilot run),
// NEEDED_SPP the spp that meets the criterion (at most max_spp); MET is yes or no.
int reference_check(const std::vector<std::string>& files, const std::vector<std::string>& layers,
                    const std::filesystem::path& reference_file, double budget, int max_spp) {
  const Image reference = read_exr(reference_file);
  const MetadataValue* done = reference.metadata.find("spp_done");
  const double* spp = done ? std::get_if<double>(done) : nullptr;
  const int* spp_int = done ? std::get_if<int>(done) : nullptr;
  if (!spp && !spp_int) throw InputError(reference_file.string(), "spp_done", "", "missing (not a `chlorovdb reference` image?)");
  const int reference_spp = spp_int ? *spp_int : int(*spp);
  for (const std::string& layer : layers) {
    const ReferenceSelfError self = reference_self_error(reference, layer);
    if (!self.available || self.mean == 0) continue;
    std::vector<VariantError> variants;
    for (const auto& [label, r] : last_rows(read_rows(files, layer))) variants.push_back({label, r.error, r.seconds});
    if (variants.empty()) throw InputError(files.empty() ? "" : files.front(), "layer", layer, "no variant has this layer");
    const ReferenceCheck c = check_reference(self.rel_mse, variants, budget);
    fmt::print("{} {} {:.4e} {:.4e} {} {:.4e} {:.4e} {} {}\n", layer, reference_spp, self.rel_mse, self.rms_stderr / std::abs(self.mean),
               c.best_label, c.best_own_rel_mse, c.share, reference_spp_needed(reference_spp, c, max_spp), c.met ? "yes" : "no");
  }
  return 0;
}

// Convergence rate and equal-effort error of each label, measured over seeds:
// every CSV is one seed's progressive run (spp 1, 2, 4, ...). Per label:
// the relMSE-vs-spp exponent fitted per seed on relMSE minus the reference's
// own share (so a finite reference does not flatten the tail; expected -1, the
// RMSE exponent being half of it), also without that correction; at the largest
// spp, relMSE and CPU time averaged over seeds, their product (lower is better:
// `vs` is baseline's product / this one's, the equal-time efficiency ratio) and
// the share of the squared error held by the worst 0.1 % of pixels (mean, max).
// The RMSE exponent is also fitted on the last `tail_octaves` octaves of spp only:
// a heavy tail whose rare paths first appear at a few tens of spp bends the
// whole-range fit while the estimator already converges at its rate above them.
int slope(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline, int tail_octaves) {
  struct Label {
    std::vector<PowerFit> corrected, raw, tail;
    std::vector<double> rel_mse, seconds, top_share, dim_share, bias;
    int spp = 0;
  };
  std::vector<std::string> order;
  std::map<std::string, Label> by_label;
  for (const std::string& file : files) {
    std::vector<Row> rows = read_rows({file}, layer);
    if (rows.empty()) continue;
    std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.spp < b.spp; });
    if (!by_label.count(rows.front().label)) order.push_back(rows.front().label);
    Label& l = by_label[rows.front().label];
    std::vector<double> spp, corrected, raw;
    for (const Row& r : rows) {
      spp.push_back(r.spp);
      corrected.push_back(own_rel_mse(r.error));
      raw.push_back(r.error.rel_mse);
    }
    l.corrected.push_back(fit_power_law(spp, corrected));
    l.raw.push_back(fit_power_law(spp, raw));
    l.tail.push_back(fit_power_law(spp, corrected, std::ldexp(double(rows.back().spp), -tail_octaves)));
    if (l.spp != 0 && l.spp != rows.back().spp) throw InputError(file, "spp", std::to_string(rows.back().spp), "seeds of one label must end at the same spp");
    l.spp = rows.back().spp;
    l.rel_mse.push_back(rows.back().error.rel_mse);
    l.seconds.push_back(rows.back().seconds);
    l.top_share.push_back(rows.back().error.top_pixel_share);
    l.dim_share.push_back(rows.back().error.dim_pixel_share_rel);
    l.bias.push_back(rows.back().relative_bias());
  }
  auto mean = [](const std::vector<double>& v) { return mean_over_runs(v).mean; };
  auto standard_error = [](const std::vector<double>& v) { return mean_over_runs(v).standard_error; };
  auto product = [&](const Label& l) { return mean(l.rel_mse) * mean(l.seconds); };
  const double base = by_label.count(baseline) ? product(by_label[baseline]) : 0.0;
  fmt::print(
      "| variant | seeds | relMSE slope (ref. share removed) | raw | RMSE slope | RMSE slope, last {} octaves "
      "| spp | relMSE | CPU s | relMSE × s | vs {} | worst 0.1 % px share (mean / max) "
      "| relMSE share of dim px | mean bias |\n",
      tail_octaves, baseline);
  fmt::print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const std::string& label : order) {
    const Label& l = by_label[label];
    const MeanOverRuns c = mean_exponent(l.corrected), r = mean_exponent(l.raw), t = mean_exponent(l.tail);
    fmt::print(
        "| {} | {} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {} | {:.3e} ± {:.1e} | "
        "{:.2f} | {:.3e} | {} "
        "| {:.1f} / {:.1f} % | {:.0f} % | {:+.1f} ± {:.1f} % |\n",
        label, c.runs, c.mean, c.standard_error, r.mean, r.standard_error, c.mean / 2, c.standard_error / 2, t.mean / 2,
        t.standard_error / 2, l.spp, mean(l.rel_mse), standard_error(l.rel_mse), mean(l.seconds), product(l),
        base > 0 && product(l) > 0 ? fmt::format("{:.2f}×", base / product(l)) : "–", 100 * mean(l.top_share),
        100 * *std::max_element(l.top_share.begin(), l.top_share.end()), 100 * mean(l.dim_share), 100 * mean(l.bias),
        100 * standard_error(l.bias));
  }
  return 0;
}

// ---- cost growth ---------------------------------------------------------

// Density pattern in [0.2, 1] (so majorants are loose and minima non-zero).
float pattern(double x, double y, double z) {
  return float(0.6 + 0.4 * std::sin(6.2831853 * 3 * x) * std::sin(6.2831853 * 2 * y) * std::cos(6.2831853 * 2.5 * z));
}

// A unit cube [-0.5, 0.5]^3 of N^3 voxels; sparse: only a ball of radius 0.3 (11 % of the cube) holds data.
void write_grid(const std::filesystem::path& path, int n, bool sparse) {
  DenseGrid g({n, n, n});
  const double h = 1.0 / n;
  g.world_from_index = Transform::translate(Vec3(float(-0.5 + h / 2))) * Transform::scale(Vec3(float(h)));
  g.metadata.name = "density";
  g.metadata.unit = "M";
  g.metadata.provenance = "chlorovdb_bench cost-growth";
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = (i + 0.5) * h - 0.5, y = (j + 0.5) * h - 0.5, z = (k + 0.5) * h - 0.5;
        const bool inside = !sparse || x * x + y * y + z * z < 0.09;
        g.at(i, j, k) = inside ? pattern(x, y, z) : 0.f;
      }
  write_concentration_grid(path, g);
}

// sigma_t = tau * density (1/m) over a 1 m cube: tau is the optical depth across
// the cube where density = 1. Albedo 0.9 when scattering, else absorbing only.
std::filesystem::path write_cube_scene(const std::filesystem::path& dir, const std::string& name,
                                       const std::string& grid, double tau, bool scattering,
                                       const std::string& transmittance) {
  const double sigma_a = scattering ? 0.1 * tau : tau, sigma_s = scattering ? 0.9 * tau : 0.0;
  const std::string scatter =
      scattering ? fmt::format(R"(, "scattering": {{"coefficient": {{"file": "{}", "name": "density", "scale": {}}}, "g": 0}})", grid, sigma_s)
                 : "";
  const std::string json = fmt::format(R"({{
  "render": {{"resolution": [32, 32], "spp": 1, "max_depth": 64, "wavelengths": 4, "transmittance": "{tr}"}},
  "camera": {{"position": [0, 0.3, 2.5], "look_at": [0, 0, 0], "fov": 35}},
  "pigments": {{"grey": {{"extinction": {eps}, "quantum_yield": 0}}}},
  "media": {{"cube": {{"solvent": "none",
    "pigments": [{{"pigment": "grey", "grid": {{"file": "{grid}", "name": "density", "unit": "M"}}}}]{scatter}}}}},
  "lights": [{{"type": "distant", "direction": [-1, -2, -1.5], "spectrum": 1, "scale": 3}},
             {{"type": "environment", "spectrum": 1, "scale": 0.25}}]
}}
)",
                                       fmt::arg("tr", transmittance), fmt::arg("eps", sigma_a / (100 * std::log(10.0))),
                                       fmt::arg("grid", grid), fmt::arg("scatter", scatter));
  const auto path = dir / (name + ".json");
  std::ofstream(path) << json;
  return path;
}

// CPU seconds (summed over threads: robust to other load on a shared machine)
// per camera sample (per pixel sample), from a render long enough to time.
double seconds_per_sample(const Scene& scene, int threads) {
  auto cpu = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  };
  auto run = [&](int spp) {
    Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
    RenderOptions o;
    o.spp = spp;
    o.threads = threads;
    o.seed = 7;
    const double t0 = cpu();
    render(scene, film, o);
    return cpu() - t0;
  };
  const double t1 = run(1);
  const int spp = int(std::clamp(0.6 / std::max(t1, 1e-6), 1.0, 256.0));
  const double t = spp == 1 ? t1 : run(spp);
  return t / (double(spp) * scene.settings.width * scene.settings.height);
}

int cost_growth(const std::filesystem::path& out, bool large, int threads) {
  std::filesystem::create_directories(out);
  const auto dir = out / "cost_growth_data";
  std::filesystem::create_directories(dir);
  std::ofstream csv(out / "cost_growth.csv");
  csv << "study,series,x,seconds_per_sample\n";
  std::string md;

  // 1. Optical depth, 64^3 dense grid.
  write_grid(dir / "dense64.vdb", 64, false);
  const std::vector<double> taus = {1, 3, 10, 30, 100, 300, 1000};
  struct Series {
    std::string name;
    bool scattering;
    std::string transmittance;
  };
  const std::vector<Series> series = {{"scattering (delta tracking, albedo 0.9)", true, "auto"},
                                      {"absorbing: ratio tracking", false, "ratio"},
                                      {"absorbing: residual ratio tracking", false, "residual_ratio"},
                                      {"absorbing: delta tracking", false, "delta"}};
  LogLogPanel tau_panel{"time per sample against optical depth (64³ grid)", "optical depth across the cube", "CPU µs per sample", {}, {}};
  md += "| series | exponent k (time ∝ τ^k) | CPU µs/sample at τ = 1 | at τ = 1000 |\n| --- | ---: | ---: | ---: |\n";
  for (const Series& s : series) {
    PlotSeries p{s.name, {}, {}};
    for (double tau : taus) {
      const auto file = write_cube_scene(dir, fmt::format("tau{}_{}", tau, s.transmittance + (s.scattering ? "_s" : "")),
                                         "dense64.vdb", tau, s.scattering, s.transmittance);
      const Scene scene = load_scene(file);
      const double t = seconds_per_sample(scene, threads);
      csv << fmt::format("optical_depth,{},{},{:.6e}\n", s.name, tau, t);
      fmt::print(stderr, "tau {:6g} {:45s} {:8.2f} µs/sample\n", tau, s.name, t * 1e6);
      p.x.push_back(tau);
      p.y.push_back(t * 1e6);
    }
    // The exponent over the thick end (tau >= 10), where tracking dominates fixed costs.
    std::vector<double> x(p.x.begin() + 2, p.x.end()), y(p.y.begin() + 2, p.y.end());
    const PowerFit fit = fit_power_law(x, y);
    md += fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} |\n", s.name, fit.exponent, p.y.front(), p.y.back());
    p.label += fmt::format(" (k = {:.2f})", fit.exponent);
    tau_panel.series.push_back(p);
  }

  // 2. Grid size at optical depth 10 (scattering), dense and sparse.
  std::vector<int> sizes = {64, 128, 256};
  if (large) sizes.push_back(512);
  LogLogPanel size_panel{"time per sample against grid size (τ = 10)", "voxels per axis N", "CPU µs per sample", {}, {}};
  md += "\n| grid | exponent k (time ∝ N^k) | " ;
  for (int n : sizes) md += fmt::format("CPU µs/sample at {}³ | ", n);
  md += "\n| --- | ---: |";
  for (size_t i = 0; i < sizes.size(); ++i) md += " ---: |";
  md += "\n";
  for (bool sparse : {false, true}) {
    PlotSeries p{sparse ? "sparse (ball, 11 % of voxels)" : "dense", {}, {}};
    for (int n : sizes) {
      const std::string grid = fmt::format("{}{}.vdb", sparse ? "sparse" : "dense", n);
      if (!std::filesystem::exists(dir / grid)) write_grid(dir / grid, n, sparse);
      const auto file = write_cube_scene(dir, fmt::format("size{}_{}", n, sparse ? "sparse" : "dense"), grid, 10, true, "auto");
      const Scene scene = load_scene(file);
      const double t = seconds_per_sample(scene, threads);
      csv << fmt::format("grid_size,{},{},{:.6e}\n", p.label, n, t);
      fmt::print(stderr, "N {:4d} {:8s} {:8.2f} µs/sample\n", n, sparse ? "sparse" : "dense", t * 1e6);
      p.x.push_back(n);
      p.y.push_back(t * 1e6);
      std::filesystem::remove(dir / grid);  // large files: keep only while measuring
    }
    const PowerFit fit = fit_power_law(p.x, p.y);
    md += fmt::format("| {} | {:.2f} |", p.label, fit.exponent);
    for (double y : p.y) md += fmt::format(" {:.2f} |", y);
    md += "\n";
    p.label += fmt::format(" (k = {:.2f})", fit.exponent);
    size_panel.series.push_back(p);
  }
  write_loglog_svg(out / "cost_growth.svg", {tau_panel, size_panel});
  std::ofstream(out / "cost_growth.md") << md;
  std::filesystem::remove_all(dir);
  fmt::print("{}", md);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"chlorovdb_bench: helpers of tools/benchmarks/run.sh"};
  app.require_subcommand(1);
  std::vector<std::string> files;
  std::string layer = "total", title, out, baseline;
  CLI::App* p = app.add_subcommand("plot", "RMSE against time and samples from converge CSVs");
  p->add_option("csv", files)->required();
  p->add_option("--layer", layer);
  p->add_option("--title", title);
  p->add_option("-o,--output", out)->required();
  std::string time_label = "render time (s)";
  p->add_option("--time-label", time_label, "x-axis label of the time panel");
  CLI::App* t = app.add_subcommand("table", "Markdown efficiency table from converge CSVs");
  t->add_option("csv", files)->required();
  t->add_option("--layer", layer);
  t->add_option("--baseline", baseline, "Label the gains are relative to");
  CLI::App* b = app.add_subcommand("best", "Most efficient label and its gain over --baseline");
  std::vector<std::string> candidates;
  b->add_option("csv", files)->required();
  b->add_option("--layer", layer);
  b->add_option("--baseline", baseline)->required();
  b->add_option("--among", candidates, "Only these labels");
  CLI::App* sl = app.add_subcommand("slope", "Convergence rate over seeds and relMSE x time from converge CSVs (one per seed)");
  sl->add_option("csv", files)->required();
  sl->add_option("--layer", layer);
  sl->add_option("--baseline", baseline, "Label the efficiency ratios are relative to");
  int tail_octaves = 4;
  sl->add_option("--tail-octaves", tail_octaves, "Also fit the rate on the last this many octaves of spp (default 4)")
      ->check(CLI::Range(1, 30));
  CLI::App* rc = app.add_subcommand("reference-check", "Whether a reference is converged enough to rank the variants of converge CSVs");
  std::vector<std::string> layers = {"total", "fluorescence"};
  std::string reference;
  double budget = 0;
  int max_spp = kMaxSpp;
  rc->add_option("csv", files)->required();
  rc->add_option("--reference", reference, "The reference EXR the CSVs were measured against")->required();
  rc->add_option("--layers", layers, "Layers to check (default: total fluorescence)");
  rc->add_option("--budget", budget, "Predict the variants' own relMSE at this time from theirs (a pilot run; default: as measured)");
  rc->add_option("--max-spp", max_spp, "Cap of the needed spp");
  CLI::App* c = app.add_subcommand("cost-growth", "Time per sample against optical depth and grid size");
  bool large = false;
  int threads = 0;
  c->add_option("-o,--output", out, "Output folder")->required();
  c->add_flag("--large", large, "Also 512³ (about 2 GB of memory, minutes)");
  c->add_option("--threads", threads);
  CLI11_PARSE(app, argc, argv);
  try {
    if (p->parsed()) return plot(files, layer, title, out, time_label);
    if (t->parsed()) return table(files, layer, baseline);
    if (b->parsed()) return best(files, layer, baseline, candidates);
    if (sl->parsed()) return slope(files, layer, baseline, tail_octaves);
    if (rc->parsed()) return reference_check(files, layers, reference, budget, max_spp);
    return cost_growth(out, large, threads);
  } catch (const std::exception& e) {
    fmt::print(stderr, "chlorovdb_bench: error: {}\n", e.what());
    return 1;
  }
}
