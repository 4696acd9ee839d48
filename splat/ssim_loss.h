#pragma once
// The structural similarity of a rendered image to a photo, and its gradient with respect to the render, for
// the splats' loss ((1 - w) L1 + w (1 - SSIM); 3D Gaussian Splatting takes w = 0.2). The window is SSIM's usual
// 11x11 Gaussian of sigma 1.5 (K1 0.01, K2 0.03, peak 1), per channel, with zeros outside the image (as the
// reference's convolution pads), so that the backward pass is the same blur and the gradient exact.

#include <memory>

namespace p2n {

// Mean SSIM over the pixels and channels of `render` against `photo` (row-major, `channels` interleaved);
// writes d(mean SSIM)/d(render) to `gradient` (same layout) when it is not null. T: float or double. The
// object keeps its buffers from call to call (a training step's images are the same size each time).
class SsimLoss {
 public:
  SsimLoss();
  ~SsimLoss();
  template <typename T>
  double operator()(const T* render, const T* photo, int width, int height, int channels, T* gradient);

 private:
  struct Buffers;  // OpenCV images, out of this header
  std::unique_ptr<Buffers> buffers_;
};

}  // namespace p2n
