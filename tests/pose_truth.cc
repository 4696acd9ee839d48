// The synthetic scene's true cameras against those the stages recovered (pose_truth.h).

#include "tests/pose_truth.h"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <cmath>

#include "base/file_util.h"

namespace p2n::testing {
namespace fs = std::filesystem;

Eigen::Matrix4d ReadMatrix(const nlohmann::json& rows) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int r = 0; r < static_cast<int>(rows.size()); ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = rows[r][c].get<double>();
  }
  return m;
}

PoseErrors CompareWithTruth(const nlohmann::json& transforms, const std::map<std::string, Eigen::Matrix4d>& truth) {
  const int n = static_cast<int>(transforms["frames"].size());
  Eigen::Matrix3Xd estimated(3, n), expected(3, n);
  std::vector<Eigen::Matrix3d> estimated_rotations, true_rotations;
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& frame = transforms["frames"][i];
    const std::string name = fs::path(frame["file_path"].get<std::string>()).filename().string();
    const Eigen::Matrix4d mine = ReadMatrix(frame["transform_matrix"]);
    const Eigen::Matrix4d theirs = truth.at(name);
    estimated.col(i) = mine.topRightCorner<3, 1>();
    expected.col(i) = theirs.topRightCorner<3, 1>();
    estimated_rotations.push_back(mine.topLeftCorner<3, 3>());
    true_rotations.push_back(theirs.topLeftCorner<3, 3>());
  }
  const Eigen::Matrix4d alignment = Eigen::umeyama(estimated, expected, true);
  const double scale = std::cbrt(alignment.topLeftCorner<3, 3>().determinant());
  const Eigen::Matrix3d rotation = alignment.topLeftCorner<3, 3>() / scale;
  const Eigen::Vector3d centroid = expected.rowwise().mean();
  const double spread = std::sqrt((expected.colwise() - centroid).colwise().squaredNorm().mean());
  PoseErrors errors;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d difference = true_rotations[i].transpose() * rotation * estimated_rotations[i];
    errors.worst_angle_deg = std::max(errors.worst_angle_deg, Eigen::AngleAxisd(difference).angle() * 180 / M_PI);
    const Eigen::Vector3d aligned = (alignment * estimated.col(i).homogeneous()).head<3>();
    errors.worst_centre = std::max(errors.worst_centre, (aligned - expected.col(i)).norm() / spread);
  }
  return errors;
}

std::map<std::string, Eigen::Matrix4d> TruePoses(const fs::path& photos) {
  const nlohmann::json truth = ReadJsonFile(photos / "ground_truth_cameras.json");
  std::map<std::string, Eigen::Matrix4d> poses;
  for (const auto& frame : truth["frames"]) poses[frame["file_path"]] = ReadMatrix(frame["transform_matrix"]);
  return poses;
}

void CheckPoses(const nlohmann::json& transforms, const std::map<std::string, Eigen::Matrix4d>& truth,
                double max_angle_deg, double max_centre, size_t views) {
  REQUIRE(transforms["frames"].size() == views);
  const PoseErrors errors = CompareWithTruth(transforms, truth);
  INFO("worst rotation error " << errors.worst_angle_deg << " deg, worst centre error " << 100 * errors.worst_centre
                               << "% of spread");
  CHECK(errors.worst_angle_deg < max_angle_deg);
  CHECK(errors.worst_centre < max_centre);
}

}  // namespace p2n::testing
