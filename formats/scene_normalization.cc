#include "formats/scene_normalization.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/float_image.h"
#include "formats/camera_geometry.h"

namespace p2n {
namespace {

constexpr double kMaxFocusAngleDeg = 30;  // above this the focus point is not what the cameras look at
constexpr double kMinAgreement = 0.3;     // |mean of unit up vectors| below this: the up vectors disagree
constexpr size_t kMinPoints = 10;
constexpr double kTiny = 1e-12;

Eigen::Vector3d Median(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d median;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    for (const Eigen::Vector3d& p : points) values.push_back(p[axis]);
    median[axis] = Quantile(values, 0.5);
  }
  return median;
}

}  // namespace

Normalization NormalizeScene(const std::vector<Eigen::Vector3d>& centres, const std::vector<Eigen::Vector3d>& ups,
                             const std::vector<Eigen::Vector3d>& axes, const std::vector<Eigen::Vector3d>& points) {
  if (centres.empty()) throw UserError("no camera to normalise the scene with");
  Normalization result;

  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  const auto focus = FindFocusPoint(centres, axes);
  if (focus && focus->median_angle_deg < kMaxFocusAngleDeg) {
    centre = focus->point;
    result.centre_from = "focus point";
  } else if (points.size() >= kMinPoints) {
    centre = Median(points);
    result.centre_from = "sparse points";
  } else {
    for (const Eigen::Vector3d& c : centres) centre += c;
    centre /= static_cast<double>(centres.size());
    result.centre_from = "cameras";
  }

  Eigen::Vector3d mean_up = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& up : ups) mean_up += up.normalized();
  mean_up /= static_cast<double>(std::max<size_t>(1, ups.size()));
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  result.up_from = "none";
  if (mean_up.norm() >= kMinAgreement) {
    up = mean_up.normalized();
    result.up_from = "camera up vectors";
  } else if (centres.size() >= 3) {
    // Cameras around an object lie near a plane whose normal is up; choose the side the cameras' ups lean to.
    const PrincipalFrame frame = PrincipalAxes(centres);
    const Eigen::Vector3d& values = frame.variances;
    if (values(1) > 1e-6 * std::max(values(2), kTiny) && values(2) > kTiny) {
      up = frame.axes.col(0);
      if (up.dot(mean_up) < 0) up = -up;
      result.up_from = "camera plane";
    }
  }
  if (result.up_from == "none") {
    result.warnings.push_back("the cameras agree on no up direction and lie on no plane; the scene is not rotated");
  }
  const Eigen::Matrix3d rotation = Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).toRotationMatrix();

  // Scale: the robust extent of the points around the centre, else of the cameras.
  std::vector<double> extents;
  for (const Eigen::Vector3d& p : points) extents.push_back((rotation * (p - centre)).cwiseAbs().maxCoeff());
  double extent = extents.size() >= kMinPoints ? Quantile(extents, 0.95) : 0;
  if (extent < kTiny) {
    std::vector<double> distances;
    for (const Eigen::Vector3d& c : centres) distances.push_back((c - centre).norm());
    extent = 0.5 * Quantile(distances, 1.0);
    if (extent >= kTiny && !points.empty()) {
      result.warnings.push_back("too few sparse points; the scale comes from the cameras");
    }
  }
  if (!(extent >= kTiny) || !std::isfinite(extent)) {
    throw UserError(
        "every camera and point of the reconstruction is at one place; photo2nerf needs photos taken "
        "from different positions");
  }
  result.scale = 1 / extent;
  result.normalized_from_world.topLeftCorner<3, 3>() = result.scale * rotation;
  result.normalized_from_world.topRightCorner<3, 1>() = -result.scale * rotation * centre;
  return result;
}

}  // namespace p2n
