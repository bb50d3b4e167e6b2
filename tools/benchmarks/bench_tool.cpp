// chlorovdb_bench: the helper behind tools/benchmarks/run.sh (not installed).
//   plot   CSV... -o OUT.svg      RMSE against time / samples, one series per CSV label
//   table  CSV... --baseline L    markdown efficiency table (last point of each label)
//   slope  CSV... --baseline L    convergence rate over seeds (one CSV per seed) and relMSE x time
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

#include "analysis/loglog_fit.h"
#include "analysis/svg_plot.h"
#include "core/error.h"
#include "grids/vdb_file.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

// ---- converge CSVs -------------------------------------------------------

struct Row {
  std::string label, layer, clock;
  int spp = 0;
  double seconds = 0, budget = 0, mse = 0, rmse = 0, rel_mse = 0, bias = 0, efficiency = 0;
  double reference_mean = 0, efficiency_rel = 0;
  double reference_rel_variance = 0, top_pixel_share = 0;  // 0 in CSVs older than these columns
  // Mean bias relative to the reference's mean, both images clamped at the
  // reference's 99.9th percentile (analysis/image_error.h): about 0 (within
  // noise) for an unbiased estimator; -1: the variant renders nothing of this layer.
  double relative_bias() const { return reference_mean != 0 ? bias / reference_mean : 0.0; }
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
                             "rel_mse", "bias", "reference_mean", "efficiency"})
      if (!col.count(need)) throw InputError(file, need, "", "missing column (not a chlorovdb converge CSV?)");
    while (std::getline(f, line)) {
      const auto c = split(line);
      if (c.size() < header.size() || c[col["layer"]] != layer) continue;
      Row r;
      r.label = c[col["label"]];
      r.clock = c[col["clock"]];
      r.spp = std::stoi(c[col["spp"]]);
      r.seconds = std::stod(c[col[c[col["clock"]] == "cpu" ? "cpu_seconds" : "wall_seconds"]]);
      r.budget = std::stod(c[col["time_budget"]]);
      r.layer = c[col["layer"]];
      r.mse = std::stod(c[col["mse"]]);
      r.rmse = std::stod(c[col["rmse"]]);
      r.rel_mse = std::stod(c[col["rel_mse"]]);
      r.bias = std::stod(c[col["bias"]]);
      r.efficiency = std::stod(c[col["efficiency"]]);
      r.reference_mean = std::stod(c[col["reference_mean"]]);
      if (col.count("bias_clamped")) {  // robust to a reference's fireflies
        r.bias = std::stod(c[col["bias_clamped"]]);
        r.reference_mean = std::stod(c[col["reference_mean_clamped"]]);
      }
      r.efficiency_rel = col.count("efficiency_rel") ? std::stod(c[col["efficiency_rel"]]) : 0.0;
      r.reference_rel_variance = col.count("reference_rel_variance") ? std::stod(c[col["reference_rel_variance"]]) : 0.0;
      r.top_pixel_share = col.count("top_pixel_share") ? std::stod(c[col["top_pixel_share"]]) : 0.0;
      rows.push_back(r);
    }
  }
  return rows;
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
        t.y.push_back(r.rmse);
        s.x.push_back(r.spp);
        s.y.push_back(r.rmse);
      }
    by_time.series.push_back(t);
    by_spp.series.push_back(s);
  }
  write_loglog_svg(out, {by_time, by_spp});
  return 0;
}

// One markdown row per label: its last (largest-effort) point. Gains are on
// 1/(relMSE x time): relMSE bounds what each pixel contributes where the
// reference itself is very bright, so a reference's few unconverged pixels
// (fireflies) cannot decide the comparison as they do MSE.
int table(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline) {
  const std::vector<Row> rows = read_rows(files, layer);
  std::vector<std::string> labels;
  std::map<std::string, Row> last;
  for (const Row& r : rows) {
    if (!last.count(r.label)) labels.push_back(r.label);
    if (!last.count(r.label) || r.seconds >= last[r.label].seconds) last[r.label] = r;
  }
  const double base = last.count(baseline) ? last[baseline].efficiency_rel : 0.0;
  const std::string clock = rows.empty() ? "wall" : rows.front().clock;
  fmt::print("| variant | spp | {} s | RMSE | relMSE | mean bias | 1/(MSE·s) | 1/(relMSE·s) | vs {} |\n",
             clock == "cpu" ? "CPU" : "wall", baseline);
  fmt::print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const std::string& label : labels) {
    const Row& r = last[label];
    fmt::print("| {} | {} | {:.2f} | {:.3e} | {:.3e} | {:+.1f} % | {:.3e} | {:.3e} | {} |\n", label, r.spp, r.seconds,
               r.rmse, r.rel_mse, 100 * r.relative_bias(), r.efficiency, r.efficiency_rel,
               base > 0 ? fmt::format("{:.2f}×", r.efficiency_rel / base) : "–");
  }
  return 0;
}

// "LABEL GAIN BIAS BASELINE_BIAS": the label with the highest 1/(relMSE x time)
// (among `candidates`, all if empty), its gain over `baseline`, and both
// relative mean biases in per cent.
int best(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline,
         const std::vector<std::string>& candidates) {
  std::map<std::string, Row> last;
  for (const Row& r : read_rows(files, layer))
    if (!last.count(r.label) || r.seconds >= last[r.label].seconds) last[r.label] = r;
  if (!last.count(baseline) || !(last[baseline].efficiency_rel > 0)) throw std::runtime_error("no baseline " + baseline);
  std::string top;
  for (const auto& [label, r] : last) {
    if (!candidates.empty() && std::find(candidates.begin(), candidates.end(), label) == candidates.end()) continue;
    if (top.empty() || r.efficiency_rel > last[top].efficiency_rel) top = label;
  }
  fmt::print("{} {:.2f} {:+.1f} {:+.1f}\n", top, last[top].efficiency_rel / last[baseline].efficiency_rel,
             100 * last[top].relative_bias(), 100 * last[baseline].relative_bias());
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
int slope(const std::vector<std::string>& files, const std::string& layer, const std::string& baseline) {
  struct Label {
    std::vector<PowerFit> corrected, raw;
    std::vector<double> rel_mse, seconds, top_share, bias;
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
      corrected.push_back(r.rel_mse - r.reference_rel_variance);
      raw.push_back(r.rel_mse);
    }
    l.corrected.push_back(fit_power_law(spp, corrected));
    l.raw.push_back(fit_power_law(spp, raw));
    if (l.spp != 0 && l.spp != rows.back().spp) throw InputError(file, "spp", std::to_string(rows.back().spp), "seeds of one label must end at the same spp");
    l.spp = rows.back().spp;
    l.rel_mse.push_back(rows.back().rel_mse);
    l.seconds.push_back(rows.back().seconds);
    l.top_share.push_back(rows.back().top_pixel_share);
    l.bias.push_back(rows.back().relative_bias());
  }
  auto mean = [](const std::vector<double>& v) { return mean_over_runs(v).mean; };
  auto standard_error = [](const std::vector<double>& v) { return mean_over_runs(v).standard_error; };
  auto product = [&](const Label& l) { return mean(l.rel_mse) * mean(l.seconds); };
  const double base = by_label.count(baseline) ? product(by_label[baseline]) : 0.0;
  fmt::print("| variant | seeds | relMSE slope (ref. share removed) | raw | RMSE slope | spp | relMSE | CPU s | relMSE × s | vs {} "
             "| worst 0.1 % px share (mean / max) | mean bias |\n",
             baseline);
  fmt::print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const std::string& label : order) {
    const Label& l = by_label[label];
    const MeanOverRuns c = mean_exponent(l.corrected), r = mean_exponent(l.raw);
    fmt::print("| {} | {} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {} | {:.3e} ± {:.1e} | {:.2f} | {:.3e} | {} | {:.1f} / {:.1f} % | "
               "{:+.1f} ± {:.1f} % |\n",
               label, c.runs, c.mean, c.standard_error, r.mean, r.standard_error, c.mean / 2, c.standard_error / 2, l.spp,
               mean(l.rel_mse), standard_error(l.rel_mse), mean(l.seconds), product(l),
               base > 0 && product(l) > 0 ? fmt::format("{:.2f}×", base / product(l)) : "–", 100 * mean(l.top_share),
               100 * *std::max_element(l.top_share.begin(), l.top_share.end()), 100 * mean(l.bias), 100 * standard_error(l.bias));
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
    if (sl->parsed()) return slope(files, layer, baseline);
    return cost_growth(out, large, threads);
  } catch (const std::exception& e) {
    fmt::print(stderr, "chlorovdb_bench: error: {}\n", e.what());
    return 1;
  }
}
