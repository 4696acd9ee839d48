#include "nerf/mesh_simplify.h"

#include <meshoptimizer.h>

#include <limits>

namespace p2n {
namespace {

// The vertices `indices` use, renumbered in order of first use.
Mesh Compact(const Mesh& mesh, const std::vector<uint32_t>& indices) {
  std::vector<uint32_t> remap(mesh.positions.size(), std::numeric_limits<uint32_t>::max());
  Mesh out;
  for (size_t i = 0; i < indices.size(); i += 3) {
    std::array<uint32_t, 3>& triangle = out.triangles.emplace_back();
    for (int c = 0; c < 3; ++c) {
      uint32_t& to = remap[indices[i + c]];
      if (to == std::numeric_limits<uint32_t>::max()) {
        to = static_cast<uint32_t>(out.positions.size());
        out.positions.push_back(mesh.positions[indices[i + c]]);
        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[indices[i + c]]);
        if (!mesh.colours.empty()) out.colours.push_back(mesh.colours[indices[i + c]]);
      }
      triangle[c] = to;
    }
  }
  return out;
}

}  // namespace

SimplifiedMesh SimplifyMesh(const Mesh& mesh, size_t max_triangles) {
  SimplifiedMesh result;
  if (mesh.triangles.size() <= max_triangles) {
    result.mesh = mesh;
    return result;
  }
  const std::vector<uint32_t> indices(mesh.triangles.front().data(), mesh.triangles.back().data() + 3);
  const float* positions = mesh.positions.front().data();
  const size_t stride = sizeof(Eigen::Vector3f), count = mesh.positions.size(), target = 3 * max_triangles;
  std::vector<uint32_t> kept(indices.size());
  float error = 0;  // relative to the mesh's extent
  // No bound on the error: the budget decides where the collapses stop.
  kept.resize(meshopt_simplify(kept.data(), indices.data(), indices.size(), positions, count, stride, target,
                               std::numeric_limits<float>::max(), 0, &error));
  if (kept.size() > target) {
    result.sloppy = true;
    const std::vector<uint32_t> from = kept;
    kept.resize(meshopt_simplifySloppy(kept.data(), from.data(), from.size(), positions, count, stride, target,
                                       std::numeric_limits<float>::max(), &error));
  }
  result.error = error * meshopt_simplifyScale(positions, count, stride);
  result.mesh = Compact(mesh, kept);
  return result;
}

}  // namespace p2n
