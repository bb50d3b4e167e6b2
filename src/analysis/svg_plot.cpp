#include "analysis/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {

namespace {

constexpr double kPanelW = 460, kPanelH = 340;
constexpr double kLeft = 70, kRight = 20, kTop = 30, kBottom = 50;  // margins inside a panel
// Colour-blind-safe palette (Okabe & Ito 2008).
constexpr const char* kColors[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"};

std::string escape(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (c == '&') r += "&amp;";
    else if (c == '<') r += "&lt;";
    else if (c == '>') r += "&gt;";
    else if (c == '"') r += "&quot;";
    else r += c;
  }
  return r;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (v > 0 && std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  bool valid() const { return lo <= hi; }
  // Whole decades around the data (at least one decade wide).
  void to_decades() {
    if (!valid()) {
      lo = 1;
      hi = 10;
    }
    lo = std::pow(10.0, std::floor(std::log10(lo) + 1e-9));
    hi = std::pow(10.0, std::ceil(std::log10(hi) - 1e-9));
    if (hi <= lo) hi = lo * 10;
  }
};

std::string decade_label(double v) {
  const int e = int(std::lround(std::log10(v)));
  if (e >= -2 && e <= 4) return fmt::format("{:g}", std::pow(10.0, e));
  return fmt::format("1e{}", e);
}

std::string panel_svg(const LogLogPanel& p, double x0) {
  Range rx, ry;
  for (const PlotSeries& s : p.series)
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (s.x[i] > 0 && s.y[i] > 0) {
        rx.add(s.x[i]);
        ry.add(s.y[i]);
      }
  rx.to_decades();
  ry.to_decades();
  const double w = kPanelW - kLeft - kRight, h = kPanelH - kTop - kBottom;
  const double lx0 = std::log10(rx.lo), lx1 = std::log10(rx.hi), ly0 = std::log10(ry.lo), ly1 = std::log10(ry.hi);
  auto X = [&](double v) { return x0 + kLeft + (std::log10(v) - lx0) / (lx1 - lx0) * w; };
  auto Y = [&](double v) { return kTop + h - (std::log10(v) - ly0) / (ly1 - ly0) * h; };

  std::string out;
  out += fmt::format("<g font-family=\"sans-serif\" font-size=\"11\">\n");
  out += fmt::format("<text x=\"{:.1f}\" y=\"18\" font-size=\"13\" text-anchor=\"middle\">{}</text>\n",
                     x0 + kLeft + w / 2, escape(p.title));
  // Grid and ticks: every decade labelled, 2..9 as faint lines.
  for (int e = int(std::lround(lx0)); e <= int(std::lround(lx1)); ++e)
    for (int m = 1; m <= 9; ++m) {
      const double v = m * std::pow(10.0, e);
      if (v < rx.lo * 0.999 || v > rx.hi * 1.001) continue;
      out += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"{3}\"/>\n", X(v),
                         kTop, kTop + h, m == 1 ? "#bbb" : "#eee");
      if (m == 1)
        out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", X(v), kTop + h + 15,
                           decade_label(v));
    }
  for (int e = int(std::lround(ly0)); e <= int(std::lround(ly1)); ++e)
    for (int m = 1; m <= 9; ++m) {
      const double v = m * std::pow(10.0, e);
      if (v < ry.lo * 0.999 || v > ry.hi * 1.001) continue;
      out += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"{3}\"/>\n",
                         x0 + kLeft, Y(v), x0 + kLeft + w, m == 1 ? "#bbb" : "#eee");
      if (m == 1)
        out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", x0 + kLeft - 5, Y(v) + 4,
                           decade_label(v));
    }
  out += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#333\"/>\n",
                     x0 + kLeft, kTop, w, h);
  out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", x0 + kLeft + w / 2,
                     kPanelH - 12, escape(p.x_label));
  out += fmt::format("<text transform=\"translate({:.1f},{:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                     x0 + 16, kTop + h / 2, escape(p.y_label));
  out += fmt::format("<clipPath id=\"clip{0:.0f}\"><rect x=\"{1:.1f}\" y=\"{2:.1f}\" width=\"{3:.1f}\" height=\"{4:.1f}\"/></clipPath>\n",
                     x0, x0 + kLeft, kTop, w, h);
  out += fmt::format("<g clip-path=\"url(#clip{:.0f})\">\n", x0);
  // The guide: slope k through the first point of the first series, across the panel.
  if (p.guide_slope && !p.series.empty()) {
    const PlotSeries& s = p.series.front();
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!(s.x[i] > 0 && s.y[i] > 0)) continue;
      const double k = *p.guide_slope;
      const double ya = s.y[i] * std::pow(rx.lo / s.x[i], k), yb = s.y[i] * std::pow(rx.hi / s.x[i], k);
      out += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#555\" "
                         "stroke-dasharray=\"6,4\"/>\n",
                         X(rx.lo), Y(ya), X(rx.hi), Y(yb));
      break;
    }
  }
  for (size_t k = 0; k < p.series.size(); ++k) {
    const PlotSeries& s = p.series[k];
    const char* color = kColors[k % std::size(kColors)];
    std::string points;
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (s.x[i] > 0 && s.y[i] > 0) points += fmt::format("{:.1f},{:.1f} ", X(s.x[i]), Y(s.y[i]));
    out += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.6\"/>\n", points, color);
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (s.x[i] > 0 && s.y[i] > 0)
        out += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>\n", X(s.x[i]), Y(s.y[i]), color);
  }
  out += "</g>\n";
  // Legend (top right, inside the axes).
  double ly = kTop + 14;
  auto legend = [&](const std::string& label, const char* color, bool dashed) {
    const double lx = x0 + kLeft + w - 150;
    out += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"1.6\"{}/>\n",
                       lx, ly - 4, lx + 18, ly - 4, color, dashed ? " stroke-dasharray=\"6,4\"" : "");
    out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n", lx + 24, ly, escape(label));
    ly += 14;
  };
  for (size_t k = 0; k < p.series.size(); ++k) {
    const PlotSeries& s = p.series[k];
    bool drawn = false;  // a series with no positive point (e.g. an all-zero layer) gets no legend entry
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) drawn = drawn || (s.x[i] > 0 && s.y[i] > 0);
    if (drawn) legend(s.label, kColors[k % std::size(kColors)], false);
  }
  if (p.guide_slope && !p.series.empty()) legend(p.guide_label, "#555", true);
  out += "</g>\n";
  return out;
}

}  // namespace

std::string loglog_svg(const std::vector<LogLogPanel>& panels) {
  const double width = kPanelW * double(std::max<size_t>(1, panels.size()));
  std::string out = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      width, kPanelH);
  for (size_t i = 0; i < panels.size(); ++i) out += panel_svg(panels[i], kPanelW * double(i));
  out += "</svg>\n";
  return out;
}

void write_loglog_svg(const std::filesystem::path& path, const std::vector<LogLogPanel>& panels) {
  std::ofstream f(path);
  if (!f) throw InputError(path.string(), "", "", "cannot be written");
  f << loglog_svg(panels);
  if (!f) throw InputError(path.string(), "", "", "write failed");
}

}  // namespace chlorovdb
