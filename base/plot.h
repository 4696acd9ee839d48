#pragma once
// Line plots written as PNG (OpenCV drawing) or SVG: for error-against-time curves.

#include <filesystem>
#include <string>
#include <vector>

#include "base/float_image.h"

namespace p2n {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;
};

struct PlotLabels {
  std::string title, x_axis, y_axis;
};

// The series of columns `x_column` and `y_column` (0-based) of CSV text with a header line; rows whose values
// are not finite numbers are left out.
PlotSeries CsvSeries(const std::string& name, const std::string& csv, int x_column, int y_column);

// Draws the series (finite points only) with axes, ticks and a legend; throws std::runtime_error naming the
// file when it cannot be written.
void WriteLinePlot(const std::filesystem::path& path, const PlotLabels& labels, const std::vector<PlotSeries>& series);

// The same plot as an SVG element (for HTML pages): axes with ticks, a title, axis labels, a legend.
std::string SvgLinePlot(const PlotLabels& labels, const std::vector<PlotSeries>& series, int width = 640,
                        int height = 360);

struct CaptionedImage {
  std::string caption;
  const FloatImage* image;
};
// The images side by side (scaled to one height), each with its caption below; PNG.
void WriteImageStrip(const std::filesystem::path& path, const std::vector<CaptionedImage>& images);

}  // namespace p2n
