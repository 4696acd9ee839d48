#pragma once
// A texture for a mesh: each pair of triangles that share an edge gets a square of the texture (they meet along its
// diagonal; a triangle without a partner takes half a square), squares sized by the area they cover and packed in
// rows; each texel is coloured by what a function says of the surface point it stands for. Every triangle's
// corners sit on texel centres, so that bilinear filtering never reads another square's texels (the texture is
// meant to be sampled without mipmaps).

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/triangle_mesh.h"

namespace p2n {

// The colours of surface points, given with their unit normals (from outside looking in along minus the normal).
using SurfaceColourFunction = std::function<std::vector<std::array<uint8_t, 3>>(
    const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals)>;

// `mesh` (with normals) textured in a `texture_size` square, the largest squares that fit. UserError when the mesh
// has too many triangles for the texture (more than about texture_size^2 / 8).
TexturedMesh BakeTexture(const Mesh& mesh, int texture_size, const SurfaceColourFunction& colour);

}  // namespace p2n
