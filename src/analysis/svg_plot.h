#pragma once
// Log-log line plots written as plain SVG (no plotting dependency): one or more
// panels side by side, each with decade grid lines, a legend, and optionally a
// dashed guide of a given slope (the ideal Monte Carlo rate -1/2) anchored at
// the first point of the first series.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace chlorovdb {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;  // points with x <= 0 or y <= 0 are not drawn
};

struct LogLogPanel {
  std::string title;
  std::string x_label, y_label;
  std::vector<PlotSeries> series;
  std::optional<double> guide_slope;  // e.g. -0.5
  std::string guide_label = "slope -1/2";
};

// The SVG document (panels left to right, each 460 x 340 px).
std::string loglog_svg(const std::vector<LogLogPanel>& panels);
// Writes loglog_svg(panels); throws InputError naming the file if it cannot be written.
void write_loglog_svg(const std::filesystem::path& path, const std::vector<LogLogPanel>& panels);

}  // namespace chlorovdb
