#include "splat/scene_size.h"

#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "base/camera.h"

namespace p2n {

bool InPicture(const PinholeCamera& camera, const float* position, double near) {
  double depth = 0;
  const Eigen::Vector2d pixel = Project(camera, Eigen::Vector3d(position[0], position[1], position[2]), &depth);
  return depth > near && pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() < camera.width && pixel.y() < camera.height;
}

double MeanViewShare(const std::vector<TrainView>& views, const Gaussians<float>& splats, double near) {
  if (views.empty() || splats.size() == 0) return 1;
  const size_t view_stride = (views.size() + kShareViews - 1) / kShareViews;
  const size_t splat_stride = (splats.size() + kShareSplats - 1) / kShareSplats;
  const size_t counted = (splats.size() + splat_stride - 1) / splat_stride;
  double sum = 0;
  size_t measured = 0;
  for (size_t v = 0; v < views.size(); v += view_stride, ++measured) {
    const PinholeCamera& camera = views[v].camera;
    sum += tbb::parallel_reduce(
               tbb::blocked_range<size_t>(0, counted), size_t(0),
               [&](const tbb::blocked_range<size_t>& range, size_t seen) {
                 for (size_t k = range.begin(); k < range.end(); ++k) {
                   seen += InPicture(camera, &splats.positions[3 * k * splat_stride], near);
                 }
                 return seen;
               },
               std::plus<>()) /
           static_cast<double>(counted);
  }
  return sum / static_cast<double>(measured);
}

}  // namespace p2n
