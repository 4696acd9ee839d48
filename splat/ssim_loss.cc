#include "splat/ssim_loss.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace p2n {
namespace {

constexpr int kWindow = 11;
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;

}  // namespace

template <typename T>
double SsimWithGradient(const T* render, const T* photo, int width, int height, int channels, T* gradient) {
  const int type = CV_MAKETYPE(cv::DataType<T>::depth, channels);
  const cv::Mat x(height, width, type, const_cast<T*>(render)), y(height, width, type, const_cast<T*>(photo));
  const cv::Mat kernel = cv::getGaussianKernel(kWindow, kSigma, cv::DataType<T>::depth);
  const auto blur = [&](const cv::Mat& m) {
    cv::Mat out;
    cv::sepFilter2D(m, out, -1, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
    return out;
  };
  const cv::Scalar c1 = cv::Scalar::all(kC1), c2 = cv::Scalar::all(kC2);  // all channels, not the first only
  const cv::Mat mu_x = blur(x), mu_y = blur(y);
  const cv::Mat var_x = blur(x.mul(x)) - mu_x.mul(mu_x), var_y = blur(y.mul(y)) - mu_y.mul(mu_y);
  const cv::Mat cov = blur(x.mul(y)) - mu_x.mul(mu_y);
  const cv::Mat n1 = 2 * mu_x.mul(mu_y) + c1, n2 = 2 * cov + c2;
  const cv::Mat d1 = mu_x.mul(mu_x) + mu_y.mul(mu_y) + c1, d2 = var_x + var_y + c2;
  cv::Mat d, ssim;
  cv::multiply(d1, d2, d);
  cv::divide(n1.mul(n2), d, ssim);
  const double count = double(width) * height * channels;
  const cv::Scalar sum = cv::sum(ssim);
  double total = 0;
  for (int c = 0; c < channels; ++c) total += sum[c];
  if (gradient == nullptr) return total / count;

  // SSIM(p) = n1 n2 / (d1 d2) depends on x through mu_x, var_x and cov, each a blur of x, x^2 or xy. With
  // a = dS/d(mu_x) - 2 mu_x dS/d(var_x) - mu_y dS/d(cov), b = dS/d(var_x), c = dS/d(cov):
  // dS/dx = blur(a) + 2 x blur(b) + y blur(c) (the window is symmetric, so the blur is its own adjoint).
  cv::Mat b, c, a_part;
  cv::divide(-ssim, d2, b);
  cv::divide(2 * n1, d, c);
  cv::divide(2 * mu_y.mul(n2), d, a_part);
  cv::Mat a_minus;
  cv::divide(2 * mu_x.mul(ssim), d1, a_minus);
  const cv::Mat a = a_part - a_minus - 2 * mu_x.mul(b) - mu_y.mul(c);
  cv::Mat out = (blur(a) + 2 * x.mul(blur(b)) + y.mul(blur(c))) / count;
  cv::Mat target(height, width, type, gradient);
  out.copyTo(target);
  return total / count;
}

template double SsimWithGradient<float>(const float*, const float*, int, int, int, float*);
template double SsimWithGradient<double>(const double*, const double*, int, int, int, double*);

}  // namespace p2n
