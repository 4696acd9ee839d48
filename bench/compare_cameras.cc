// Compares the cameras of two transforms.json files (camera-to-world, OpenGL axes), matched by image file name:
// - centre error after a similarity alignment of the camera centres (Umeyama), relative to the reference cameras'
//   spread (the RMS distance from their centroid);
// - rotation error (degrees) under that alignment's rotation; where the centres lie near a line or a flat arc (a
//   facade walked past) they fix the rotation about it poorly, so that error can be the alignment's, not the cameras';
// - rotation error under the rotation that best aligns the orientations themselves (the chordal mean of each
//   reference rotation times the estimated one's inverse);
// - relative rotation error over every pair of cameras, which no alignment enters.
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

double AngleDeg(const Eigen::Matrix3d& rotation) { return Eigen::AngleAxisd(rotation).angle() * 180 / M_PI; }

// The rotation nearest (in the Frobenius norm) to a 3 x 3 matrix.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

void PrintErrors(const char* what, const std::vector<double>& degrees) {
  std::printf("%s: median %.3f deg, max %.3f deg\n", what, Median(degrees),
              *std::max_element(degrees.begin(), degrees.end()));
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
    std::vector<Eigen::Matrix3d> est(n), ref(n);
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (Eigen::Index i = 0; i < n; ++i) {
      est[i] = estimated.at(names[i]).topLeftCorner<3, 3>();
      ref[i] = reference.at(names[i]).topLeftCorner<3, 3>();
      sum += ref[i] * est[i].transpose();
    }
    const Eigen::Matrix3d best_rotation = NearestRotation(sum);
    std::vector<double> by_centres, by_rotations, relative, centres;
    for (Eigen::Index i = 0; i < n; ++i) {
      by_centres.push_back(AngleDeg(ref[i].transpose() * rotation * est[i]));
      by_rotations.push_back(AngleDeg(ref[i].transpose() * best_rotation * est[i]));
      for (Eigen::Index j = i + 1; j < n; ++j) {
        relative.push_back(AngleDeg((ref[i].transpose() * ref[j]).transpose() * (est[i].transpose() * est[j])));
      }
      centres.push_back(((alignment * source.col(i).homogeneous()).head<3>() - target.col(i)).norm() / spread);
    }
    std::printf("cameras compared: %zu (estimated %zu, reference %zu)\n", names.size(), estimated.size(),
                reference.size());
    PrintErrors("rotation error (centres aligned)", by_centres);
    PrintErrors("rotation error (rotations aligned)", by_rotations);
    PrintErrors("relative rotation error (every pair)", relative);
    std::printf("centre error: median %.3f%%, max %.3f%% of the camera spread\n", 100 * Median(centres),
                100 * *std::max_element(centres.begin(), centres.end()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "compare_cameras: %s\n", e.what());
    return 1;
  }
  return 0;
}
