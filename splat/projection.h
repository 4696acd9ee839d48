#pragma once
// One Gaussian seen by one camera: its 2D mean, the inverse of its 2D covariance (the "conic"), opacity and
// colour, as the rasterizer blends them; and the backward pass from the gradients of those to the Gaussian's
// parameters. The 2D covariance is J W Σ Wᵀ Jᵀ + dilation · I (EWA splatting; J the perspective Jacobian at
// the mean, W the camera's rotation, Σ = R S Sᵀ Rᵀ), as 3D Gaussian Splatting does. The camera looks along +z
// (OpenCV axes); pixel (i, j)'s centre is at (i + 0.5, j + 0.5).

#include <Eigen/Core>

#include "base/camera.h"
#include "splat/gaussians.h"

namespace p2n {

// A camera prepared for projection, in scalar type T.
template <typename T>
struct SplatCamera {
  Eigen::Matrix<T, 3, 3> rotation;     // cam_from_world, OpenCV axes
  Eigen::Matrix<T, 3, 1> translation;  // cam_from_world
  Eigen::Matrix<T, 3, 1> centre;       // the camera's position in the world
  T fx, fy, cx, cy;
  int width = 0, height = 0;
  // The Jacobian is taken at x/z and y/z clamped to these (30% beyond the image's edges, as the reference
  // code does): a Gaussian far outside the view does not get an enormous footprint.
  T min_x, max_x, min_y, max_y;

  static SplatCamera From(const PinholeCamera& camera);
};

struct ProjectionOptions {
  double near = 0.01;     // Gaussians nearer than this (world units along the view axis) are not drawn
  double dilation = 0.3;  // pixels² added to the 2D covariance's diagonal (a pixel's footprint)
  int sh_degree = 3;      // the highest degree used (at most the Gaussians'), for training coarse to fine
};

// What the rasterizer blends of one projected Gaussian.
template <typename T>
struct Splat2D {
  T x = 0, y = 0;                           // mean, pixels
  T conic_a = 0, conic_b = 0, conic_c = 0;  // inverse 2D covariance [[a, b], [b, c]]
  T opacity = 0;
  T rgb[3] = {0, 0, 0};
  T depth = 0;  // along the view axis (not differentiated: the backward pass ignores it)
};

// Projects Gaussian `i`; false when it is not drawn (behind the near plane, or not finite). `depth` is along the
// view axis and `radius` (pixels) bounds 3 standard deviations of its footprint.
template <typename T>
bool ProjectGaussian(const Gaussians<T>& gaussians, size_t i, const SplatCamera<T>& camera,
                     const ProjectionOptions& options, Splat2D<T>* splat, T* depth, T* radius);

// Adds to `grads` (shaped like `gaussians`) the gradient of Gaussian `i`'s parameters, given `grad`, the
// gradient of its Splat2D (as ProjectGaussian computed it; the colour's gradient is zero where it was clamped
// to 0).
template <typename T>
void ProjectGaussianBackward(const Gaussians<T>& gaussians, size_t i, const SplatCamera<T>& camera,
                             const ProjectionOptions& options, const Splat2D<T>& grad, Gaussians<T>* grads);

}  // namespace p2n
