// How close the export's mesh lies to the synthetic scene's true surfaces. The workspace must be trained from the
// scene's true cameras (make_synthetic_scene DIR N, then DIR/ground_truth_cameras.json copied to DIR/transforms.json
// and `photo2nerf run DIR -w WS`), so that the mesh's source frame is the scene's own. Prints, in scene units and as
// a share of the side of the cube meshed: accuracy (mesh to truth: mean, median, 95th percentile, max, and the
// share of the mesh's area farther than 5% of the side: floaters), completeness (truth to mesh over the true
// surfaces inside the cube: mean, median, and the share within 1%), chamfer (their means' mean) and normal
// consistency (the mean of |n_mesh . n_true|).
// Usage: surface_bench WORKSPACE

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <unordered_map>

#include "base/file_util.h"
#include "base/float_image.h"
#include "examples/synthetic_scene.h"
#include "formats/dataset_import.h"
#include "stages/stage_reports.h"

namespace fs = std::filesystem;
using namespace p2n;

namespace {

struct MeshFile {
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<int32_t, 3>> triangles;
};

// Our mesh.ply (formats/mesh_io.cc's layout: x y z nx ny nz as floats, r g b as bytes; faces of three int32).
MeshFile ReadOurMeshPly(const fs::path& path) {
  const std::string data = ReadTextFile(path);
  const size_t header_end = data.find("end_header\n") + 11;
  size_t vertices = 0, faces = 0;
  std::sscanf(data.c_str() + data.find("element vertex"), "element vertex %zu", &vertices);
  std::sscanf(data.c_str() + data.find("element face"), "element face %zu", &faces);
  MeshFile mesh;
  size_t at = header_end;
  for (size_t v = 0; v < vertices; ++v, at += 27) {
    Eigen::Vector3f& p = mesh.positions.emplace_back();
    std::memcpy(p.data(), &data[at], 12);
  }
  for (size_t f = 0; f < faces; ++f, at += 13) std::memcpy(mesh.triangles.emplace_back().data(), &data[at + 1], 12);
  return mesh;
}

// Points hashed into cubes of `cell`: the nearest of them to a query, searched out to `limit`.
class PointHash {
 public:
  PointHash(const std::vector<Eigen::Vector3d>& points, double cell) : points_(points), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i) cells_[Key(Cell(points[i]))].push_back(i);
  }
  double Nearest(const Eigen::Vector3d& query, double limit) const {
    const Eigen::Vector3i centre = Cell(query);
    double best = limit;
    const int reach = static_cast<int>(std::ceil(limit / cell_));
    for (int ring = 0; ring <= reach && ring * cell_ - cell_ < best; ++ring) {
      for (int dx = -ring; dx <= ring; ++dx) {
        for (int dy = -ring; dy <= ring; ++dy) {
          for (int dz = -ring; dz <= ring; ++dz) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
            const auto found = cells_.find(Key(centre + Eigen::Vector3i(dx, dy, dz)));
            if (found == cells_.end()) continue;
            for (const size_t i : found->second) best = std::min(best, (points_[i] - query).norm());
          }
        }
      }
    }
    return best;
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const { return (p / cell_).array().floor().cast<int>(); }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (int64_t(c.x()) & 0x1fffff) << 42 | (int64_t(c.y()) & 0x1fffff) << 21 | (int64_t(c.z()) & 0x1fffff);
  }
  const std::vector<Eigen::Vector3d>& points_;
  double cell_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

Eigen::Vector3d TrueNormal(const Eigen::Vector3d& p) {
  constexpr double h = 1e-5;
  Eigen::Vector3d g;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(a);
    g[a] = SyntheticSignedDistance(p + e) - SyntheticSignedDistance(p - e);
  }
  return g.normalized();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: surface_bench WORKSPACE\n");
    return 2;
  }
  const fs::path workspace = argv[1];
  const ExportReport exported = ExportReport::Read(workspace / "50_export" / "export_report.json");
  if (exported.frame != FrameKind::kSource) {
    std::fprintf(stderr, "surface_bench: the export must be in the source frame (export.frame source)\n");
    return 2;
  }
  const ImportedDataset poses = LoadTransformsJson(workspace / "20_poses" / "transforms.json", workspace);
  const Eigen::Matrix4d normalized_from_world = poses.meta.normalization.normalized_from_world;
  const double scale = std::cbrt(normalized_from_world.topLeftCorner<3, 3>().determinant());
  const Eigen::Vector3d centre(exported.mesh.centre[0], exported.mesh.centre[1], exported.mesh.centre[2]);
  const double side = 2 * exported.mesh.half_size / scale;  // scene units
  const auto in_cube = [&](const Eigen::Vector3d& world) {
    const Eigen::Vector3d n = (normalized_from_world * world.homogeneous()).head<3>();
    return (n - centre).cwiseAbs().maxCoeff() <= exported.mesh.half_size;
  };

  // Accuracy and normals: points spread over the mesh by area.
  const MeshFile mesh = ReadOurMeshPly(workspace / "50_export" / "mesh.ply");
  std::vector<double> area(mesh.triangles.size());
  double total_area = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& c = mesh.triangles[t];
    const Eigen::Vector3d a = mesh.positions[c[0]].cast<double>();
    area[t] = 0.5 * (mesh.positions[c[1]].cast<double>() - a).cross(mesh.positions[c[2]].cast<double>() - a).norm();
    total_area += area[t];
  }
  std::mt19937 random(1);
  std::discrete_distribution<size_t> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> samples;
  std::vector<double> accuracy, consistency;
  for (int s = 0; s < 400000; ++s) {
    const auto& c = mesh.triangles[pick(random)];
    double u = unit(random), v = unit(random);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Eigen::Vector3d a = mesh.positions[c[0]].cast<double>(), b = mesh.positions[c[1]].cast<double>(),
                          d = mesh.positions[c[2]].cast<double>();
    const Eigen::Vector3d p = a + u * (b - a) + v * (d - a);
    samples.push_back(p);
    accuracy.push_back(std::abs(SyntheticSignedDistance(p)));
    consistency.push_back(std::abs((b - a).cross(d - a).normalized().dot(TrueNormal(p))));
  }
  const double floaters = std::count_if(accuracy.begin(), accuracy.end(), [&](double e) { return e > 0.05 * side; }) /
                          double(accuracy.size());

  // Completeness: the true surfaces inside the cube, to the nearest mesh sample.
  const PointHash hash(samples, 0.01 * side);
  std::vector<double> completeness;
  for (const Eigen::Vector3d& p : SyntheticSurfacePoints(0.005 * side)) {
    if (in_cube(p)) completeness.push_back(hash.Nearest(p, 0.2 * side));
  }
  const double within =
      std::count_if(completeness.begin(), completeness.end(), [&](double e) { return e < 0.01 * side; }) /
      double(completeness.size());

  const double acc = Mean(accuracy), comp = Mean(completeness);
  std::printf("mesh: %zu triangles, area %.3f; cube side %.3f scene units\n", mesh.triangles.size(), total_area, side);
  std::printf(
      "accuracy (mesh to truth): mean %.4f (%.2f%% of the side), median %.4f, 95th %.4f, max %.4f; "
      "%.2f%% of the area farther than 5%% of the side\n",
      acc, 100 * acc / side, Quantile(accuracy, 0.5), Quantile(accuracy, 0.95),
      *std::max_element(accuracy.begin(), accuracy.end()), 100 * floaters);
  std::printf(
      "completeness (truth to mesh, %zu points): mean %.4f (%.2f%%), median %.4f; %.1f%% within 1%% of the "
      "side\n",
      completeness.size(), comp, 100 * comp / side, Quantile(completeness, 0.5), 100 * within);
  std::printf("chamfer %.4f (%.2f%% of the side); normal consistency %.3f\n", (acc + comp) / 2,
              50 * (acc + comp) / side, Mean(consistency));
  return 0;
}
