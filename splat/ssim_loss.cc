#include "splat/ssim_loss.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace p2n {
namespace {

constexpr int kWindow = 11;
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;

// Every channel of `in` blurred by the window into `out`, zero outside the image.
void Blur(const cv::Mat& in, const cv::Mat& kernel, cv::Mat* out) {
  cv::sepFilter2D(in, *out, -1, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
}

}  // namespace

struct SsimLoss::Buffers {
  cv::Mat moments, means, partials, blurred;
};

SsimLoss::SsimLoss() : buffers_(std::make_unique<Buffers>()) {}
SsimLoss::~SsimLoss() = default;

template <typename T>
double SsimLoss::operator()(const T* render, const T* photo, int width, int height, int channels, T* gradient) {
  const int depth = cv::DataType<T>::depth;
  const size_t pixels = size_t(width) * height;
  const cv::Mat kernel = cv::getGaussianKernel(kWindow, kSigma, depth);
  // Per pixel and channel: x, y, x^2, y^2, xy, blurred together.
  cv::Mat& moments = buffers_->moments;
  moments.create(height, width, CV_MAKETYPE(depth, 5 * channels));
  tbb::parallel_for(size_t{0}, pixels * channels, [&](size_t i) {
    T* m = moments.ptr<T>() + 5 * i;
    const T x = render[i], y = photo[i];
    m[0] = x, m[1] = y, m[2] = x * x, m[3] = y * y, m[4] = x * y;
  });
  cv::Mat& means = buffers_->means;
  Blur(moments, kernel, &means);

  // SSIM(p) = n1 n2 / (d1 d2) depends on x through mu_x, var_x and cov, each a blur of x, x^2 or xy. With
  // a = dS/d(mu_x) - 2 mu_x dS/d(var_x) - mu_y dS/d(cov), b = dS/d(var_x), c = dS/d(cov):
  // dS/dx = blur(a) + 2 x blur(b) + y blur(c) (the window is symmetric, so the blur is its own adjoint).
  cv::Mat& partials = buffers_->partials;
  partials.create(height, width, CV_MAKETYPE(depth, 3 * channels));
  const double total = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, pixels * channels), 0.0,
      [&](const tbb::blocked_range<size_t>& range, double sum) {
        for (size_t i = range.begin(); i < range.end(); ++i) {
          const T* m = means.ptr<T>() + 5 * i;
          const T mu_x = m[0], mu_y = m[1];
          const T var_x = m[2] - mu_x * mu_x, var_y = m[3] - mu_y * mu_y, cov = m[4] - mu_x * mu_y;
          const T n1 = 2 * mu_x * mu_y + T(kC1), n2 = 2 * cov + T(kC2);
          const T d1 = mu_x * mu_x + mu_y * mu_y + T(kC1), d2 = var_x + var_y + T(kC2);
          const T ssim = n1 * n2 / (d1 * d2);
          sum += ssim;
          T* p = partials.ptr<T>() + 3 * i;
          const T b = -ssim / d2, c = 2 * n1 / (d1 * d2);
          p[0] = 2 * mu_y * n2 / (d1 * d2) - 2 * mu_x * ssim / d1 - 2 * mu_x * b - mu_y * c;
          p[1] = b;
          p[2] = c;
        }
        return sum;
      },
      std::plus<double>());
  const double count = double(pixels) * channels;
  if (gradient == nullptr) return total / count;

  cv::Mat& blurred = buffers_->blurred;
  Blur(partials, kernel, &blurred);
  tbb::parallel_for(size_t{0}, pixels * channels, [&](size_t i) {
    const T* p = blurred.ptr<T>() + 3 * i;
    gradient[i] = static_cast<T>((p[0] + 2 * render[i] * p[1] + photo[i] * p[2]) / count);
  });
  return total / count;
}

template double SsimLoss::operator()(const float*, const float*, int, int, int, float*);
template double SsimLoss::operator()(const double*, const double*, int, int, int, double*);

}  // namespace p2n
