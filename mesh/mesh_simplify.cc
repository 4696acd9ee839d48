#include "mesh/mesh_simplify.h"

#include <meshoptimizer.h>

#include <cstring>
#include <limits>

#include "mesh/mesh.h"

namespace p2n {

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
  std::vector<std::array<uint32_t, 3>> triangles(kept.size() / 3);
  std::memcpy(triangles.data(), kept.data(), kept.size() * sizeof(uint32_t));
  result.mesh = WithTriangles(mesh, triangles);
  return result;
}

}  // namespace p2n
