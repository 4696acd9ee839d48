// libFuzzer: the textured mesh's glTF writer round trip. A mesh made from the input (any float values, triangles
// naming its vertices) is written as .glb and read back by tinygltf: the same positions and triangles bit for bit,
// the texture coordinates as 16-bit fractions, and the texture.
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "formats/gltf_io.h"

namespace {

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "round trip failed: %s\n", what);
  std::abort();
}

// The bytes accessor `index` covers.
std::string AccessorBytes(const tinygltf::Model& model, int index, size_t element_size) {
  const tinygltf::Accessor& accessor = model.accessors.at(index);
  const tinygltf::BufferView& view = model.bufferViews.at(accessor.bufferView);
  const std::vector<unsigned char>& data = model.buffers.at(view.buffer).data;
  const size_t first = view.byteOffset + accessor.byteOffset, size = accessor.count * element_size;
  if (first + size > data.size()) Fail("an accessor reaches past the buffer");
  return std::string(reinterpret_cast<const char*>(data.data()) + first, size);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // 20 bytes a vertex (position, texture coordinates); the rest names triangles' corners.
  p2n::TexturedMesh mesh;
  const size_t vertices = std::min<size_t>(size / 20, 64);
  for (size_t v = 0; v < vertices; ++v) {
    float values[5];
    std::memcpy(values, data + 20 * v, sizeof(values));
    mesh.positions.emplace_back(values[0], values[1], values[2]);
    mesh.uvs.emplace_back(values[3], values[4]);
  }
  for (size_t at = 20 * vertices; vertices > 0 && at + 3 <= size; at += 3) {
    mesh.triangles.push_back(
        {uint32_t(data[at] % vertices), uint32_t(data[at + 1] % vertices), uint32_t(data[at + 2] % vertices)});
  }
  mesh.texture_size = 8;
  mesh.texture.assign(3 * 8 * 8, 128);
  static const std::string jpeg = p2n::TextureJpeg(mesh);
  const std::string glb = p2n::MeshGlbBytes(mesh, jpeg, "fuzz");

  tinygltf::Model model;
  std::string error, warning;
  if (!tinygltf::TinyGLTF().LoadBinaryFromMemory(&model, &error, &warning,
                                                 reinterpret_cast<const unsigned char*>(glb.data()),
                                                 static_cast<unsigned>(glb.size()))) {
    std::fprintf(stderr, "%s\n", error.c_str());
    Fail("tinygltf cannot read what we wrote");
  }
  const tinygltf::Primitive& primitive = model.meshes.at(0).primitives.at(0);
  const auto same = [&](int accessor, const void* values, size_t bytes, size_t element_size) {
    return AccessorBytes(model, accessor, element_size) == std::string(static_cast<const char*>(values), bytes);
  };
  if (!same(primitive.attributes.at("POSITION"), mesh.positions.data(), 12 * vertices, 12)) Fail("positions");
  std::vector<uint16_t> uvs;  // as the writer quantises them
  for (const Eigen::Vector2f& uv : mesh.uvs) {
    for (int k = 0; k < 2; ++k) uvs.push_back(uv[k] > 0 ? uint16_t(std::lround(std::min(uv[k], 1.0f) * 65535)) : 0);
  }
  if (!same(primitive.attributes.at("TEXCOORD_0"), uvs.data(), 4 * vertices, 4)) Fail("texture coordinates");
  if (!same(primitive.indices, mesh.triangles.data(), 12 * mesh.triangles.size(), 4)) Fail("triangles");
  if (model.images.size() != 1 || model.images[0].width != 8) Fail("the texture");
  return 0;
}
