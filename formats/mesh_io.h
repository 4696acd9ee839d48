#pragma once
// Meshes as files MeshLab, Blender and CloudCompare open: binary little-endian PLY (positions, normals,
// colours, triangles) and Wavefront OBJ with its material file (positions, texture coordinates, normals, triangles;
// the texture an image beside it).

#include <filesystem>
#include <string>
#include <vector>

#include "base/triangle_mesh.h"

namespace p2n {

// UserError naming the file when it cannot be written. `comments` go into the header.
void WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments);
// `path` (.obj) and its material file beside it (.mtl), whose colour is `texture_file` (a name in the same folder).
void WriteTexturedObj(const std::filesystem::path& path, const TexturedMesh& mesh, const std::string& texture_file,
                      const std::vector<std::string>& comments);

}  // namespace p2n
