// Compares the cameras of two transforms.json files (camera-to-world, OpenGL axes), matched by image file name,
// after a similarity alignment of the camera centres (Umeyama): rotation error (degrees) and centre error
// (relative to the reference cameras' spread, the RMS distance from their centroid).
// Usage: compare_cameras ESTIMATED.json REFERENCE.json

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

namespace {

std::map<std::string, Eigen::Matrix4d> Poses(const char* path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(std::string("cannot read ") + path);
  const nlohmann::json transforms = nlohmann::json::parse(in);
  std::map<std::string, Eigen::Matrix4d> poses;
  for (const auto& frame : transforms.at("frames")) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = frame.at("transform_matrix")[r][c].get<double>();
    }
    poses[std::filesystem::path(frame.at("file_path").get<std::string>()).filename().string()] = m;
  }
  return poses;
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: compare_cameras ESTIMATED.json REFERENCE.json\n");
    return 1;
  }
  try {
    const auto estimated = Poses(argv[1]);
    const auto reference = Poses(argv[2]);
    std::vector<std::string> names;
    for (const auto& [name, pose] : estimated) {
      if (reference.count(name)) names.push_back(name);
    }
    if (names.size() < 3) throw std::runtime_error("fewer than 3 cameras in common");
    const Eigen::Index n = static_cast<Eigen::Index>(names.size());
    Eigen::Matrix3Xd source(3, n), target(3, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      source.col(i) = estimated.at(names[i]).topRightCorner<3, 1>();
      target.col(i) = reference.at(names[i]).topRightCorner<3, 1>();
    }
    const Eigen::Matrix4d alignment = Eigen::umeyama(source, target, true);
    const double scale = std::cbrt(alignment.topLeftCorner<3, 3>().determinant());
    const Eigen::Matrix3d rotation = alignment.topLeftCorner<3, 3>() / scale;
    const Eigen::Vector3d centroid = target.rowwise().mean();
    const double spread = std::sqrt((target.colwise() - centroid).colwise().squaredNorm().mean());
    std::vector<double> angles, centres;
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Matrix3d difference = reference.at(names[i]).topLeftCorner<3, 3>().transpose() * rotation *
                                         estimated.at(names[i]).topLeftCorner<3, 3>();
      angles.push_back(Eigen::AngleAxisd(difference).angle() * 180 / M_PI);
      centres.push_back(((alignment * source.col(i).homogeneous()).head<3>() - target.col(i)).norm() / spread);
    }
    std::printf("cameras compared: %zu (estimated %zu, reference %zu)\n", names.size(), estimated.size(),
                reference.size());
    std::printf("rotation error: median %.3f deg, max %.3f deg\n", Median(angles),
                *std::max_element(angles.begin(), angles.end()));
    std::printf("centre error: median %.3f%%, max %.3f%% of the camera spread\n", 100 * Median(centres),
                100 * *std::max_element(centres.begin(), centres.end()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "compare_cameras: %s\n", e.what());
    return 1;
  }
  return 0;
}
