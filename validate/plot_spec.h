// A plot that a check attaches to its result. The report generator (reports/) turns it into
// an SVG with gnuplot; the data also goes into results.json so a figure can be remade.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tb {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::vector<double> y_err;        // optional error bars (same length as y), drawn as ±
  std::string style = "linespoints"; // gnuplot style: lines, points, linespoints, boxes, steps
};

struct PlotSpec {
  std::string title;
  std::string x_label, y_label;
  bool log_x = false, log_y = false;
  std::vector<PlotSeries> series;
  // Optional heat map (row-major, rows = y), drawn instead of series when non-empty.
  std::vector<std::vector<double>> heatmap;
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;  // heat map extent
};

void to_json(nlohmann::json& j, const PlotSeries& s);
void to_json(nlohmann::json& j, const PlotSpec& p);

}  // namespace tb
