#include "studies/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace knotwork {

std::string loglog_svg(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                       const std::vector<PlotSeries>& series) {
  const double W = 640, H = 480, left = 80, right = 160, top = 50, bottom = 60;
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size(); ++i)
      if (s.x[i] > 0 && s.y[i] > 0 && std::isfinite(s.y[i])) {
        xmin = std::min(xmin, s.x[i]); xmax = std::max(xmax, s.x[i]);
        ymin = std::min(ymin, s.y[i]); ymax = std::max(ymax, s.y[i]);
      }
  if (xmin > xmax) { xmin = ymin = 0.1; xmax = ymax = 1; }
  const double lx0 = std::floor(std::log10(xmin)), lx1 = std::max(std::ceil(std::log10(xmax)), lx0 + 1);
  const double ly0 = std::floor(std::log10(ymin)), ly1 = std::max(std::ceil(std::log10(ymax)), ly0 + 1);
  auto X = [&](double x) { return left + (std::log10(x) - lx0) / (lx1 - lx0) * (W - left - right); };
  auto Y = [&](double y) { return H - bottom - (std::log10(y) - ly0) / (ly1 - ly0) * (H - top - bottom); };
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << "<text x=\"" << (left + (W - left - right) / 2) << "\" y=\"25\" text-anchor=\"middle\" font-size=\"15\">"
    << title << "</text>\n";
  for (double e = lx0; e <= lx1; e += 1) {
    s << "<line x1=\"" << X(std::pow(10, e)) << "\" y1=\"" << top << "\" x2=\"" << X(std::pow(10, e)) << "\" y2=\""
      << H - bottom << "\" stroke=\"#ddd\"/>\n";
    s << "<text x=\"" << X(std::pow(10, e)) << "\" y=\"" << H - bottom + 18 << "\" text-anchor=\"middle\">1e" << e << "</text>\n";
  }
  const int ystep = std::max(1, static_cast<int>((ly1 - ly0) / 10));
  for (double e = ly0; e <= ly1; e += ystep) {
    s << "<line x1=\"" << left << "\" y1=\"" << Y(std::pow(10, e)) << "\" x2=\"" << W - right << "\" y2=\""
      << Y(std::pow(10, e)) << "\" stroke=\"#ddd\"/>\n";
    s << "<text x=\"" << left - 6 << "\" y=\"" << Y(std::pow(10, e)) + 4 << "\" text-anchor=\"end\">1e" << e << "</text>\n";
  }
  s << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << W - left - right << "\" height=\""
    << H - top - bottom << "\" fill=\"none\" stroke=\"black\"/>\n";
  s << "<text x=\"" << (left + (W - left - right) / 2) << "\" y=\"" << H - 15 << "\" text-anchor=\"middle\">" << xlabel << "</text>\n";
  s << "<text transform=\"translate(20," << (top + (H - top - bottom) / 2) << ") rotate(-90)\" text-anchor=\"middle\">" << ylabel << "</text>\n";
  for (size_t k = 0; k < series.size(); ++k) {
    const auto& sr = series[k];
    s << "<polyline fill=\"none\" stroke=\"" << sr.color << "\" stroke-width=\"2\" points=\"";
    for (size_t i = 0; i < sr.x.size(); ++i)
      if (sr.x[i] > 0 && sr.y[i] > 0 && std::isfinite(sr.y[i])) s << X(sr.x[i]) << "," << Y(sr.y[i]) << " ";
    s << "\"/>\n";
    for (size_t i = 0; i < sr.x.size(); ++i)
      if (sr.x[i] > 0 && sr.y[i] > 0 && std::isfinite(sr.y[i]))
        s << "<circle cx=\"" << X(sr.x[i]) << "\" cy=\"" << Y(sr.y[i]) << "\" r=\"3.5\" fill=\"" << sr.color << "\"/>\n";
    const double ly = top + 20 + 20 * k;
    s << "<line x1=\"" << W - right + 12 << "\" y1=\"" << ly << "\" x2=\"" << W - right + 36 << "\" y2=\"" << ly
      << "\" stroke=\"" << sr.color << "\" stroke-width=\"2\"/>\n";
    s << "<text x=\"" << W - right + 42 << "\" y=\"" << ly + 4 << "\">" << sr.label << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

}  // namespace knotwork
