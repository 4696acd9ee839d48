#pragma once
// Meshes as files MeshLab, Blender and CloudCompare open: binary little-endian PLY (positions, normals,
// colours, triangles) and Wavefront OBJ (positions with colours, normals, triangles).

#include <filesystem>
#include <string>
#include <vector>

#include "base/triangle_mesh.h"

namespace p2n {

// UserError naming the file when it cannot be written. `comments` go into the header.
void WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments);
void WriteMeshObj(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments);

}  // namespace p2n
