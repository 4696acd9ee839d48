#include "nerf/float_image.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "nerf/image_io.h"

namespace p2n {

void SaveFloatImage(const FloatImage& image, const std::filesystem::path& path, bool sixteen_bits) {
  OIIO::ImageBuf buffer(OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
                        const_cast<float*>(image.pixels.data()));
  OIIO::ImageBuf quantised(OIIO::ImageSpec(image.width, image.height, image.channels,
                                           sixteen_bits ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8));
  quantised.copy_pixels(OIIO::ImageBufAlgo::clamp(buffer, 0.0f, 1.0f));
  const std::string error = WriteImage(quantised, path);
  if (!error.empty()) throw std::runtime_error(error);
}

void SaveFloatImageExr(const FloatImage& image, const std::filesystem::path& path) {
  OIIO::ImageBuf buffer(OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
                        const_cast<float*>(image.pixels.data()));
  const std::string error = WriteImage(buffer, path);
  if (!error.empty()) throw std::runtime_error(error);
}

namespace {

void CheckSameSize(const FloatImage& a, const FloatImage& b, const char* what) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels || a.pixels.size() != b.pixels.size()) {
    throw std::invalid_argument(std::string(what) + " of images of different sizes");
  }
}

cv::Mat AsMat(const FloatImage& image) {
  return cv::Mat(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.pixels.data()));
}

}  // namespace

double Psnr(const FloatImage& a, const FloatImage& b) {
  CheckSameSize(a, b, "PSNR");
  double squared_error = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = a.pixels[i] - b.pixels[i];
    squared_error += d * d;
  }
  return PsnrOfMse(squared_error / a.pixels.size());
}

double PsnrOfMse(double mse) { return -10 * std::log10(std::max(mse, 1e-20)); }

double Mean(const std::vector<double>& values) {
  return values.empty() ? std::nan("") : std::accumulate(values.begin(), values.end(), 0.0) / values.size();
}

double Quantile(std::vector<double> values, double q) {
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

double Ssim(const FloatImage& a, const FloatImage& b) {
  CheckSameSize(a, b, "SSIM");
  constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;
  cv::Mat x, y;
  AsMat(a).convertTo(x, CV_64F);
  AsMat(b).convertTo(y, CV_64F);
  const auto blur = [](const cv::Mat& m) {
    cv::Mat out;
    cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
    return out;
  };
  const cv::Mat mu_x = blur(x), mu_y = blur(y);
  const cv::Mat mu_xx = mu_x.mul(mu_x), mu_yy = mu_y.mul(mu_y), mu_xy = mu_x.mul(mu_y);
  const cv::Mat var_x = blur(x.mul(x)) - mu_xx, var_y = blur(y.mul(y)) - mu_yy, cov = blur(x.mul(y)) - mu_xy;
  // Constants as Scalar::all: a bare number added to a multi-channel Mat goes to the first channel only.
  const cv::Scalar c1 = cv::Scalar::all(kC1), c2 = cv::Scalar::all(kC2);
  cv::Mat numerator = (2 * mu_xy + c1).mul(2 * cov + c2);
  cv::Mat denominator = (mu_xx + mu_yy + c1).mul(var_x + var_y + c2);
  cv::Mat ssim;
  cv::divide(numerator, denominator, ssim);
  const cv::Scalar mean = cv::mean(ssim);
  double sum = 0;
  for (int c = 0; c < a.channels; ++c) sum += mean[c];
  return sum / a.channels;
}

FloatImage ErrorHeatMap(const FloatImage& a, const FloatImage& b, float max_error) {
  CheckSameSize(a, b, "an error map");
  cv::Mat error8(a.height, a.width, CV_8UC1);
  for (int i = 0; i < a.width * a.height; ++i) {
    float sum = 0;
    for (int c = 0; c < a.channels; ++c)
      sum += std::abs(a.pixels[size_t(i) * a.channels + c] - b.pixels[size_t(i) * a.channels + c]);
    error8.data[i] = static_cast<uint8_t>(std::lround(255 * std::clamp(sum / a.channels / max_error, 0.0f, 1.0f)));
  }
  cv::Mat coloured;
  cv::applyColorMap(error8, coloured, cv::COLORMAP_INFERNO);  // BGR
  FloatImage map{a.width, a.height, 3, std::vector<float>(size_t(a.width) * a.height * 3)};
  for (int i = 0; i < a.width * a.height; ++i) {
    for (int c = 0; c < 3; ++c) map.pixels[size_t(i) * 3 + c] = coloured.data[size_t(i) * 3 + 2 - c] / 255.0f;
  }
  return map;
}

}  // namespace p2n
