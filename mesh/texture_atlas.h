#pragma once
// A texture for a mesh: the surface cut into charts (connected triangles facing within 45 degrees of the first one,
// wider where a rough surface makes too many small charts to fit),
// each laid flat by projecting it along that direction, the charts packed in rows at the one scale (texels per
// unit) that fills the texture; each texel a triangle covers is coloured by what a function says of the surface
// point it stands for, and the texels round each chart repeat its edge (a gutter of kGutter texels) so that
// filtering and multisampling near the edges read the chart's own colours.

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/triangle_mesh.h"

namespace p2n {

// The colours of surface points, given with their unit normals (from outside looking in along minus the normal).
using SurfaceColourFunction = std::function<std::vector<std::array<uint8_t, 3>>(
    const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals)>;

// `mesh` (with normals) textured in a `texture_size` square. UserError when its charts cannot all fit.
TexturedMesh BakeTexture(const Mesh& mesh, int texture_size, const SurfaceColourFunction& colour);

}  // namespace p2n
