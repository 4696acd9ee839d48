#pragma once
// A textured mesh as glTF 2.0 binary (.glb), the file Blender, three.js, <model-viewer>, Unity, Unreal and phones'
// AR viewers open: positions, texture coordinates and triangles in one buffer, the texture image (JPEG) embedded as
// an unlit material's base colour (KHR_materials_unlit: the texture holds the light the scene gives off, so no
// normals are needed), sampled linearly without mipmaps (TexturedMesh's squares sit side by side).

#include <filesystem>
#include <string>

#include "base/triangle_mesh.h"

namespace p2n {

// The mesh's texture as a JPEG file (quality 95, colour at full resolution: the charts' edges stay apart); UserError
// naming the file when it cannot be written.
void WriteTextureJpeg(const TexturedMesh& mesh, const std::filesystem::path& path);

// `texture_jpeg`: the texture as a JPEG file's bytes. `generator` names what wrote it (the asset's generator).
// UserError naming the file when it cannot be written.
void WriteMeshGlb(const std::filesystem::path& path, const TexturedMesh& mesh, const std::string& texture_jpeg,
                  const std::string& generator);

}  // namespace p2n
