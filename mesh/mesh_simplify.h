#pragma once
// Fewer triangles for the same surface: meshoptimizer's edge collapses, ordered by their quadric error, down to a
// triangle budget. The vertices kept are some of the input's, with their normals and colours.

#include <cstddef>

#include "base/triangle_mesh.h"

namespace p2n {

struct SimplifiedMesh {
  Mesh mesh;
  double error = 0;     // the largest distance a collapse moved the surface, in the mesh's units
  bool sloppy = false;  // the collapses stopped above the budget (at the mesh's topology); vertices were clustered
};

// `mesh` with at most `max_triangles` triangles (as it is when it has no more); unused vertices dropped.
SimplifiedMesh SimplifyMesh(const Mesh& mesh, size_t max_triangles);

}  // namespace p2n
