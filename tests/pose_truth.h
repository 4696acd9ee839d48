#pragma once
// The synthetic scene's true cameras against those the sfm and poses stages recovered: the tests of COLMAP's
// mappers, run here or as Slurm jobs.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>

namespace p2n::testing {

// A transform_matrix (4 rows of 4, or 3 with the last row implied).
Eigen::Matrix4d ReadMatrix(const nlohmann::json& rows);

// The worst rotation (degrees) and camera-centre error (fraction of the cameras' spread) of the poses stage's
// transforms.json against the true world_from_cam of each image name, after the best similarity alignment.
struct PoseErrors {
  double worst_angle_deg = 0, worst_centre = 0;
};
PoseErrors CompareWithTruth(const nlohmann::json& transforms, const std::map<std::string, Eigen::Matrix4d>& truth);

// The synthetic scene's true world_from_cam of each view by file name (its ground_truth_cameras.json in `photos`).
std::map<std::string, Eigen::Matrix4d> TruePoses(const std::filesystem::path& photos);

// All `views` in transforms.json, within `max_angle_deg` and `max_centre` (fraction of the spread) of the truth.
void CheckPoses(const nlohmann::json& transforms, const std::map<std::string, Eigen::Matrix4d>& truth,
                double max_angle_deg, double max_centre, size_t views = 24);

}  // namespace p2n::testing
