#pragma once
#include <string>
#include <vector>

namespace knotwork {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::string color;
};

// A log-log plot as a standalone SVG (no plotting dependency): one polyline with
// markers per series, decade grid lines, axis labels and a legend.
std::string loglog_svg(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                       const std::vector<PlotSeries>& series);

}  // namespace knotwork
