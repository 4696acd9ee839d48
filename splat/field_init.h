#pragma once
// Gaussians where a trained radiance field says the surfaces are: the training views are rendered small, and
// each pixel opaque enough gives a point at its median depth with its rendered colour (the background seen
// through it taken out) and the normal of the depth map there, if another view sees the same depth there (a
// floater in front of one view is not where the others see a surface). The points are pooled in cubic cells whose size
// follows the pixel footprint there (a power of two times it, the same for all, grown until the cells are few
// enough), one Gaussian per cell: the mean and colour of its points, a flat disc across the cell along their mean
// normal (a ball where the normals disagree), an opacity from the field's. Far surfaces of a real capture get
// larger and fewer Gaussians than near ones, as a photo resolves them.

#include <functional>
#include <vector>

#include "nerf/nerf_model.h"
#include "nerf/renderer.h"
#include "nerf/trainer.h"
#include "splat/gaussians.h"

namespace p2n {

struct FieldInitOptions {
  double min_opacity = 0.5;        // pixels at least this opaque give points
  int min_views = 2;               // ... if at least this many views (their own included) see them at that depth
  size_t max_gaussians = 100'000;  // the cells grow until there are at most this many
  int sh_degree = 3;               // of the Gaussians made (the higher coefficients start at zero)
};

// `renders[i]`: `model`'s image of `cameras[i]` with median depths (RenderOptions::median_depth), cameras in the
// field's (normalised) frame, small (stages/view_renders.h). The Gaussians are in the same frame.
Gaussians<float> GaussiansFromRenders(const NerfModel& model, const std::vector<PinholeCamera>& cameras,
                                      const std::vector<RenderedView>& renders, const FieldInitOptions& options);

// The same from given points (each with a colour in [0, 1] and the world size of a pixel there): what
// GaussiansFromRenders does after reading the renders, and what an initialisation from sparse points uses.
struct SurfacePoint {
  Eigen::Vector3d position;
  Eigen::Vector3f rgb;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // unit, towards the camera that saw it; zero: unknown
  float opacity = 1;
  double footprint = 0;  // world units
};
Gaussians<float> GaussiansFromPoints(const std::vector<SurfacePoint>& points, size_t max_gaussians, int sh_degree);

// 3D Gaussian Splatting's initialisation, for comparison: a ball at each sparse point (colours in [0, 1]), of
// about the distance to its three nearest neighbours, opacity 0.1 (points closer than that share one).
Gaussians<float> GaussiansFromSparsePoints(const std::vector<Eigen::Vector3d>& points,
                                           const std::vector<Eigen::Vector3f>& rgb, size_t max_gaussians,
                                           int sh_degree);

}  // namespace p2n
