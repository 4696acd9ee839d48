#include "mesh/mesh.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>

#include "base/declared_fields.h"
#include "base/float_image.h"
#include "nerf/denormals.h"

namespace p2n {
namespace {

using Matrix = RadianceField<float>::Matrix;

constexpr size_t kBatch = 4096;
constexpr size_t kMinCubePoints = 100;  // FitCube: fewer points leave the cube as it is
constexpr double kCubeQuantile = 0.05;  // the cube spans these quantiles of the points along each axis ...
constexpr double kCubeMargin = 1.2;     // ... its longest side widened by this factor

// The level set threshold - density (negative inside) on the lattice, sampled slice by slice; empty space is
// left to the grid's background value (density 0).
openvdb::FloatGrid::Ptr SampleLevelSet(const NerfModel& model, const MeshOptions& options,
                                       const std::function<void(size_t)>& on_slices_done) {
  const int n = options.resolution;
  openvdb::initialize();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(options.density_threshold);
  std::mutex grid_mutex;
  tbb::parallel_for(0, n, [&](int i) {
    std::vector<Eigen::Vector3d> points;
    std::vector<openvdb::Coord> coords;
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d p = LatticePoint(options, i, j, k);
        if (!model.occupancy.Occupied(FieldPoint(model, p))) continue;
        points.push_back(p);
        coords.emplace_back(i, j, k);
      }
    }
    const std::vector<float> density = DensitiesAt(model, points);
    std::lock_guard<std::mutex> lock(grid_mutex);
    openvdb::FloatGrid::Accessor accessor = grid->getAccessor();
    for (size_t s = 0; s < points.size(); ++s) {
      if (density[s] > 1e-4f * options.density_threshold) {
        accessor.setValue(coords[s], options.density_threshold - density[s]);
      }
    }
    if (on_slices_done) on_slices_done(1);  // under the lock: the caller's callback need not be thread-safe
  });
  return grid;
}

// The level set's zero crossing as triangles in world units, degenerate ones left out.
Mesh Polygonize(const openvdb::FloatGrid& grid, const MeshOptions& options) {
  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(grid, vertices, triangles, quads, 0.0, 0.0);
  Mesh mesh;
  mesh.positions.reserve(vertices.size());
  // Where the surface is cut by the box, the cap interpolates to the empty space beyond the last samples: it is
  // put on the box's face.
  const Eigen::Vector3d low = options.centre.array() - options.half_size;
  const Eigen::Vector3d high = options.centre.array() + options.half_size;
  for (const openvdb::Vec3s& v : vertices) {
    mesh.positions.push_back(LatticePoint(options, v.x(), v.y(), v.z()).cwiseMax(low).cwiseMin(high).cast<float>());
  }
  // OpenVDB orders a polygon's corners counter-clockwise seen from the side where the level set is positive
  // (outside).
  const auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    if (a == b || b == c || a == c) return;
    const Eigen::Vector3f& pa = mesh.positions[a];
    if ((mesh.positions[b] - pa).cross(mesh.positions[c] - pa).squaredNorm() == 0.0f) return;
    mesh.triangles.push_back({a, b, c});
  };
  for (const openvdb::Vec3I& t : triangles) add(t[0], t[1], t[2]);
  for (const openvdb::Vec4I& q : quads) {
    add(q[0], q[1], q[2]);
    add(q[0], q[2], q[3]);
  }
  return mesh;
}

// Normals from the density gradient (central differences over `h`), then colours seen from outside along them.
void Shade(const NerfModel& model, double h, Mesh* mesh) {
  std::vector<Eigen::Vector3d> probes;
  probes.reserve(6 * mesh->positions.size());
  for (const Eigen::Vector3f& p : mesh->positions) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {1.0, -1.0}) probes.push_back(p.cast<double>() + sign * h * Eigen::Vector3d::Unit(axis));
    }
  }
  const std::vector<float> probe_density = DensitiesAt(model, probes);
  mesh->normals.resize(mesh->positions.size());
  for (size_t v = 0; v < mesh->positions.size(); ++v) {
    Eigen::Vector3f gradient;
    for (int axis = 0; axis < 3; ++axis)
      gradient[axis] = probe_density[6 * v + 2 * axis] - probe_density[6 * v + 2 * axis + 1];
    const Eigen::Vector3f normal = -gradient;
    mesh->normals[v] = normal.norm() > 0 && normal.allFinite() ? normal.normalized() : Eigen::Vector3f::UnitZ();
  }
  mesh->colours = SurfaceColours(model, mesh->positions, mesh->normals);
}

// Vertex normals from the triangles around each vertex (weighted by their area), pointing out.
void NormalsFromTriangles(Mesh* mesh) {
  mesh->normals.assign(mesh->positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh->triangles) {
    const Eigen::Vector3f& a = mesh->positions[t[0]];
    const Eigen::Vector3f area = (mesh->positions[t[1]] - a).cross(mesh->positions[t[2]] - a);
    for (const uint32_t v : t) mesh->normals[v] += area;
  }
  for (Eigen::Vector3f& n : mesh->normals) n = n.norm() > 0 ? n.normalized() : Eigen::Vector3f::UnitZ();
}

}  // namespace

Eigen::Vector3d LatticePoint(const MeshOptions& options, double i, double j, double k) {
  const double spacing = 2.0 / options.resolution;
  const Eigen::Vector3d unit(-1 + (i + 0.5) * spacing, -1 + (j + 0.5) * spacing, -1 + (k + 0.5) * spacing);
  return options.centre + options.half_size * unit;
}

std::vector<std::array<uint8_t, 3>> SurfaceColours(const NerfModel& model, const std::vector<Eigen::Vector3f>& points,
                                                   const std::vector<Eigen::Vector3f>& normals) {
  std::vector<std::array<uint8_t, 3>> colours(points.size());
  tbb::parallel_for(size_t{0}, (points.size() + kBatch - 1) / kBatch, [&](size_t batch) {
    FlushDenormalsOnThisThread();
    const size_t first = batch * kBatch, count = std::min(points.size(), first + kBatch) - first;
    Matrix positions(3, count), directions(3, count), density, rgb;
    RadianceField<float>::Cache cache;
    for (size_t i = 0; i < count; ++i) {
      positions.col(i) = FieldPoint(model, points[first + i].cast<double>()).cast<float>();
      directions.col(i) = -normals[first + i];
    }
    model.field->Forward(positions, directions, &density, &rgb, &cache);
    for (size_t i = 0; i < count; ++i) {
      for (int c = 0; c < 3; ++c) {
        colours[first + i][c] = static_cast<uint8_t>(std::lround(255 * std::clamp(rgb(c, i), 0.0f, 1.0f)));
      }
    }
  });
  return colours;
}

void FitCube(const std::vector<Eigen::Vector3d>& points, MeshOptions* options, bool beyond_box) {
  if (points.size() < kMinCubePoints) return;
  Eigen::Vector3d low, high;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    values.reserve(points.size());
    for (const Eigen::Vector3d& p : points) values.push_back(p[axis]);
    low[axis] = Quantile(values, kCubeQuantile);
    high[axis] = Quantile(values, 1 - kCubeQuantile);
  }
  const Eigen::Vector3d inside_low = low.cwiseMax(-1.0), inside_high = high.cwiseMin(1.0);
  if ((inside_high - inside_low).minCoeff() > 0) {
    options->half_size = std::min(1.0, 0.5 * kCubeMargin * (inside_high - inside_low).maxCoeff());
    const double room = 1 - options->half_size;
    options->centre = (0.5 * (inside_low + inside_high)).cwiseMax(-room).cwiseMin(room);
  } else if (beyond_box && (high - low).minCoeff() >= 0 && (high - low).maxCoeff() > 0) {
    options->half_size = 0.5 * kCubeMargin * (high - low).maxCoeff();
    options->centre = 0.5 * (low + high);
  }
}

std::vector<float> DensitiesAt(const NerfModel& model, const std::vector<Eigen::Vector3d>& points) {
  std::vector<float> density(points.size(), 0.0f);
  tbb::parallel_for(size_t{0}, (points.size() + kBatch - 1) / kBatch, [&](size_t batch) {
    FlushDenormalsOnThisThread();
    const size_t first = batch * kBatch, count = std::min(points.size(), first + kBatch) - first;
    Matrix positions(3, count), out;
    for (size_t i = 0; i < count; ++i) positions.col(i) = FieldPoint(model, points[first + i]).cast<float>();
    model.field->Density(positions, &out);
    for (size_t i = 0; i < count; ++i) density[first + i] = out(0, i);
  });
  return density;
}

float SurfaceThreshold(const NerfModel& model, const std::vector<Eigen::Vector3d>& surface_points) {
  std::vector<float> density = DensitiesAt(model, surface_points);
  if (density.empty()) return 0;
  std::nth_element(density.begin(), density.begin() + density.size() / 2, density.end());
  return 0.5f * density[density.size() / 2];
}

void MeshOptions::Check() const {
  CheckField(*this, resolution, resolution >= 8 && resolution <= 1024, "must be 8..1024");
  CheckField(*this, density_threshold, density_threshold > 0 && std::isfinite(density_threshold), "must be positive");
  CheckField(*this, half_size, half_size > 0 && std::isfinite(half_size), "must be positive");
  CheckField(*this, centre, centre.allFinite(), "must be finite");
}

Mesh ExtractMesh(const NerfModel& model, const MeshOptions& options,
                 const std::function<void(size_t)>& on_slices_done) {
  options.Check();
  const openvdb::FloatGrid::Ptr grid = SampleLevelSet(model, options, on_slices_done);
  Mesh mesh = Polygonize(*grid, options);
  Shade(model, 0.1 * 2.0 * options.half_size / options.resolution, &mesh);  // a tenth of a cell
  return mesh;
}

Mesh WithTriangles(const Mesh& mesh, const std::vector<std::array<uint32_t, 3>>& triangles) {
  std::vector<uint32_t> renumbered(mesh.positions.size(), std::numeric_limits<uint32_t>::max());
  Mesh out;
  for (const auto& triangle : triangles) {
    std::array<uint32_t, 3>& corners = out.triangles.emplace_back();
    for (int c = 0; c < 3; ++c) {
      uint32_t& to = renumbered[triangle[c]];
      if (to == std::numeric_limits<uint32_t>::max()) {
        to = static_cast<uint32_t>(out.positions.size());
        out.positions.push_back(mesh.positions[triangle[c]]);
        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[triangle[c]]);
        if (!mesh.colours.empty()) out.colours.push_back(mesh.colours[triangle[c]]);
      }
      corners[c] = to;
    }
  }
  return out;
}

Mesh ExtractFusedSurface(const NerfModel& model, const MeshOptions& options, const std::vector<float>& level_set) {
  const int n = options.resolution;
  openvdb::initialize();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(1.0f);
  openvdb::FloatGrid::Accessor accessor = grid->getAccessor();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const float value = level_set[(size_t(i) * n + j) * n + k];
        if (value != 1.0f) accessor.setValue(openvdb::Coord(i, j, k), value);
      }
    }
  }
  Mesh mesh = Polygonize(*grid, options);
  // A triangle is of the surface where its cell lies inside the lattice (not a cap on the cube's faces) and one of
  // the cell's corners is near a surface some view saw (not a step between saturated values).
  std::vector<std::array<uint32_t, 3>> kept;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f centroid = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3;
    // The lattice cell it lies in: LatticePoint inverted.
    const Eigen::Vector3d cell =
        ((centroid.cast<double>() - options.centre) / options.half_size + Eigen::Vector3d::Ones()) * n / 2.0 -
        Eigen::Vector3d::Constant(0.5);
    const int i = int(std::floor(cell.x())), j = int(std::floor(cell.y())), k = int(std::floor(cell.z()));
    if (i < 0 || j < 0 || k < 0 || i + 1 >= n || j + 1 >= n || k + 1 >= n) continue;
    bool near = false;
    for (int corner = 0; corner < 8 && !near; ++corner) {
      near = std::abs(level_set[(size_t(i + (corner & 1)) * n + j + (corner >> 1 & 1)) * n + k + (corner >> 2 & 1)]) <
             1.0f;
    }
    if (near) kept.push_back(t);
  }
  mesh = WithTriangles(mesh, kept);
  NormalsFromTriangles(&mesh);
  mesh.colours = SurfaceColours(model, mesh.positions, mesh.normals);
  return mesh;
}

MeshEdges CountEdges(const Mesh& mesh) {
  // For each undirected edge (low, high): how often it is run low -> high and high -> low.
  std::map<std::pair<uint32_t, uint32_t>, std::array<int, 2>> runs;
  for (const auto& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = t[e], b = t[(e + 1) % 3];
      ++runs[{std::min(a, b), std::max(a, b)}][a < b ? 0 : 1];
    }
  }
  MeshEdges count;
  count.edges = runs.size();
  for (const auto& [edge, directions] : runs) {
    const int uses = directions[0] + directions[1];
    count.border += uses == 1;
    count.non_manifold += uses > 2;
    count.misoriented += uses == 2 && directions[0] != 1;
  }
  return count;
}

}  // namespace p2n
