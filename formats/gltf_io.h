#pragma once
// A textured mesh as glTF 2.0 binary (.glb), the file Blender, three.js, <model-viewer>, Unity, Unreal and phones'
// AR viewers open: positions, texture coordinates (16-bit fractions) and triangles in one buffer, the texture image
// (JPEG) embedded as an unlit material's base colour (KHR_materials_unlit: the texture holds the light the scene
// gives off, so no normals are needed), sampled linearly without mipmaps (the texture's charts sit side by side).

#include <string>

#include "base/triangle_mesh.h"

namespace p2n {

// The mesh's texture as a JPEG file's bytes (quality 95, colour at full resolution: the charts' edges stay apart).
std::string TextureJpeg(const TexturedMesh& mesh);

// The .glb file's bytes. `texture_jpeg`: the texture as a JPEG file's bytes (TextureJpeg); `generator` names what
// wrote it (the asset's generator). std::runtime_error if the writer fails.
std::string MeshGlbBytes(const TexturedMesh& mesh, const std::string& texture_jpeg, const std::string& generator);

}  // namespace p2n
