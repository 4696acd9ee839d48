#include "base/plot.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "base/image_io.h"

namespace p2n {
namespace {

constexpr int kWidth = 900, kHeight = 560;
constexpr int kLeft = 80, kRight = 220, kTop = 50, kBottom = 60;
const cv::Scalar kColours[] = {{200, 80, 30},  {40, 120, 230},  {60, 170, 60}, {180, 60, 180},
                               {30, 180, 200}, {120, 120, 120}, {0, 0, 200},   {140, 90, 20}};

// A "nice" tick spacing for a range: 1, 2 or 5 times a power of ten.
double TickStep(double range) {
  const double raw = range / 6;
  const double magnitude = std::pow(10, std::floor(std::log10(raw)));
  for (double factor : {1.0, 2.0, 5.0}) {
    if (factor * magnitude >= raw) return factor * magnitude;
  }
  return 10 * magnitude;
}

// Axis ranges rounded out to whole ticks, over the finite points of every series.
struct Axes {
  double x_min, x_max, y_min, y_max, x_step, y_step;
};

Axes FitAxes(const std::vector<PlotSeries>& series) {
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min, y_min = x_min, y_max = -x_min;
  for (const PlotSeries& s : series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_min = std::min(x_min, s.x[i]);
      x_max = std::max(x_max, s.x[i]);
      y_min = std::min(y_min, s.y[i]);
      y_max = std::max(y_max, s.y[i]);
    }
  }
  if (!std::isfinite(x_min)) x_min = 0, x_max = 1, y_min = 0, y_max = 1;
  if (x_max - x_min < 1e-12) x_max = x_min + 1;
  if (y_max - y_min < 1e-12) y_max = y_min + 1;
  Axes axes;
  axes.x_step = TickStep(x_max - x_min);
  axes.y_step = TickStep(y_max - y_min);
  axes.x_min = std::floor(x_min / axes.x_step) * axes.x_step;
  axes.x_max = std::ceil(x_max / axes.x_step) * axes.x_step;
  axes.y_min = std::floor(y_min / axes.y_step) * axes.y_step;
  axes.y_max = std::ceil(y_max / axes.y_step) * axes.y_step;
  return axes;
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", std::abs(value) < 1e-12 ? 0.0 : value);
  return text;
}

// Writes an 8-bit BGR picture (OpenCV's drawing order) through base/image_io.
void WriteBgr(const cv::Mat& bgr, const std::filesystem::path& path) {
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  const OIIO::ImageBuf image(OIIO::ImageSpec(rgb.cols, rgb.rows, 3, OIIO::TypeDesc::UINT8), rgb.data);
  const std::string error = WriteImage(image, path);
  if (!error.empty()) throw std::runtime_error("cannot write '" + path.string() + "': " + error);
}

void Text(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.45) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, {30, 30, 30}, 1, cv::LINE_AA);
}

}  // namespace

void WriteLinePlot(const std::filesystem::path& path, const PlotLabels& labels, const std::vector<PlotSeries>& series) {
  const Axes axes = FitAxes(series);
  const double x_min = axes.x_min, x_max = axes.x_max, y_min = axes.y_min, y_max = axes.y_max;
  const double x_step = axes.x_step, y_step = axes.y_step;

  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const int plot_width = kWidth - kLeft - kRight, plot_height = kHeight - kTop - kBottom;
  const auto to_pixel = [&](double x, double y) {
    return cv::Point(kLeft + static_cast<int>(std::lround((x - x_min) / (x_max - x_min) * plot_width)),
                     kTop + plot_height - static_cast<int>(std::lround((y - y_min) / (y_max - y_min) * plot_height)));
  };
  for (double x = x_min; x <= x_max + 1e-9 * x_step; x += x_step) {
    const cv::Point p = to_pixel(x, y_min);
    cv::line(image, {p.x, kTop}, {p.x, kTop + plot_height}, {230, 230, 230});
    Text(image, Number(x), {p.x - 10, kTop + plot_height + 20});
  }
  for (double y = y_min; y <= y_max + 1e-9 * y_step; y += y_step) {
    const cv::Point p = to_pixel(x_min, y);
    cv::line(image, {kLeft, p.y}, {kLeft + plot_width, p.y}, {230, 230, 230});
    Text(image, Number(y), {10, p.y + 5});
  }
  cv::rectangle(image, {kLeft, kTop}, {kLeft + plot_width, kTop + plot_height}, {60, 60, 60});
  Text(image, labels.title, {kLeft, 22}, 0.6);
  Text(image, labels.x_axis, {kLeft + plot_width / 2 - 40, kHeight - 15});
  Text(image, labels.y_axis, {10, kTop - 12});
  for (size_t k = 0; k < series.size(); ++k) {
    const cv::Scalar colour = kColours[k % std::size(kColours)];
    std::vector<cv::Point> points;
    for (size_t i = 0; i < series[k].x.size() && i < series[k].y.size(); ++i) {
      if (std::isfinite(series[k].x[i]) && std::isfinite(series[k].y[i])) {
        points.push_back(to_pixel(series[k].x[i], series[k].y[i]));
      }
    }
    cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
    const int legend_y = kTop + 20 + 22 * static_cast<int>(k);
    cv::line(image, {kWidth - kRight + 15, legend_y - 4}, {kWidth - kRight + 40, legend_y - 4}, colour, 2);
    Text(image, series[k].name, {kWidth - kRight + 45, legend_y});
  }
  WriteBgr(image, path);
}

std::string SvgLinePlot(const PlotLabels& labels, const std::vector<PlotSeries>& series, int width, int height) {
  constexpr int kSvgLeft = 60, kSvgRight = 20, kSvgTop = 36, kSvgBottom = 46;
  static const char* kSvgColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#7f7f7f"};
  const Axes a = FitAxes(series);
  const double plot_width = width - kSvgLeft - kSvgRight, plot_height = height - kSvgTop - kSvgBottom;
  const auto px = [&](double x) { return kSvgLeft + (x - a.x_min) / (a.x_max - a.x_min) * plot_width; };
  const auto py = [&](double y) { return kSvgTop + plot_height - (y - a.y_min) / (a.y_max - a.y_min) * plot_height; };
  const auto escape = [](const std::string& text) {
    std::string out;
    for (char c : text) out += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
    return out;
  };
  std::ostringstream svg;
  svg.imbue(std::locale::classic());
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << width << " " << height << "\" width=\"" << width
      << "\" height=\"" << height << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg << "<text x=\"" << kSvgLeft << "\" y=\"20\" font-size=\"14\" font-weight=\"bold\">" << escape(labels.title)
      << "</text>\n";
  for (double x = a.x_min; x <= a.x_max + 1e-9 * a.x_step; x += a.x_step) {
    svg << "<line x1=\"" << px(x) << "\" y1=\"" << kSvgTop << "\" x2=\"" << px(x) << "\" y2=\"" << kSvgTop + plot_height
        << "\" stroke=\"#e6e6e6\"/><text x=\"" << px(x) << "\" y=\"" << kSvgTop + plot_height + 16
        << "\" text-anchor=\"middle\">" << Number(x) << "</text>\n";
  }
  for (double y = a.y_min; y <= a.y_max + 1e-9 * a.y_step; y += a.y_step) {
    svg << "<line x1=\"" << kSvgLeft << "\" y1=\"" << py(y) << "\" x2=\"" << kSvgLeft + plot_width << "\" y2=\""
        << py(y) << "\" stroke=\"#e6e6e6\"/><text x=\"" << kSvgLeft - 6 << "\" y=\"" << py(y) + 4
        << "\" text-anchor=\"end\">" << Number(y) << "</text>\n";
  }
  svg << "<rect x=\"" << kSvgLeft << "\" y=\"" << kSvgTop << "\" width=\"" << plot_width << "\" height=\""
      << plot_height << "\" fill=\"none\" stroke=\"#444\"/>\n";
  svg << "<text x=\"" << kSvgLeft + plot_width / 2 << "\" y=\"" << height - 8 << "\" text-anchor=\"middle\">"
      << escape(labels.x_axis) << "</text>\n";
  svg << "<text transform=\"translate(14," << kSvgTop + plot_height / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
      << escape(labels.y_axis) << "</text>\n";
  for (size_t k = 0; k < series.size(); ++k) {
    const char* colour = kSvgColours[k % std::size(kSvgColours)];
    svg << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"2\" points=\"";
    for (size_t i = 0; i < series[k].x.size() && i < series[k].y.size(); ++i) {
      if (std::isfinite(series[k].x[i]) && std::isfinite(series[k].y[i]))
        svg << px(series[k].x[i]) << "," << py(series[k].y[i]) << " ";
    }
    svg << "\"/>\n<text x=\"" << kSvgLeft + plot_width - 8 << "\" y=\"" << kSvgTop + 18 + 16 * k
        << "\" text-anchor=\"end\" fill=\"" << colour << "\">" << escape(series[k].name) << "</text>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

void WriteImageStrip(const std::filesystem::path& path, const std::vector<CaptionedImage>& images) {
  constexpr int kCaption = 28;
  int height = 0;
  for (const CaptionedImage& item : images) height = std::max(height, std::min(item.image->height, 400));
  std::vector<cv::Mat> tiles;
  for (const CaptionedImage& item : images) {
    const FloatImage& image = *item.image;
    cv::Mat floats(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.pixels.data()));
    cv::Mat bytes, colour, scaled;
    floats.convertTo(bytes, CV_8U, 255.0);
    cv::cvtColor(bytes, colour, image.channels == 1 ? cv::COLOR_GRAY2BGR : cv::COLOR_RGB2BGR);
    const int width =
        std::max(1, static_cast<int>(std::lround(static_cast<double>(image.width) * height / image.height)));
    cv::resize(colour, scaled, {width, height}, 0, 0, cv::INTER_AREA);
    cv::Mat tile(height + kCaption, width + 6, CV_8UC3, cv::Scalar(255, 255, 255));
    scaled.copyTo(tile(cv::Rect(3, 0, width, height)));
    Text(tile, item.caption, {6, height + 19});
    tiles.push_back(tile);
  }
  cv::Mat strip;
  cv::hconcat(tiles, strip);
  WriteBgr(strip, path);
}

PlotSeries CsvSeries(const std::string& name, const std::string& csv, int x_column, int y_column) {
  PlotSeries series{name, {}, {}};
  std::istringstream rows(csv);
  std::string row;
  std::getline(rows, row);  // the header
  while (std::getline(rows, row)) {
    std::vector<double> values;
    std::istringstream cells(row);
    for (std::string cell; std::getline(cells, cell, ',');) values.push_back(std::strtod(cell.c_str(), nullptr));
    const int needed = std::max(x_column, y_column);
    if (static_cast<int>(values.size()) > needed && std::isfinite(values[x_column]) &&
        std::isfinite(values[y_column])) {
      series.x.push_back(values[x_column]);
      series.y.push_back(values[y_column]);
    }
  }
  return series;
}

}  // namespace p2n
