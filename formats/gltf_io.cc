#include "formats/gltf_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "base/gltf_building.h"

namespace p2n {
namespace {

constexpr int kLinear = 9729;  // glTF's sampler filter without mipmaps (the GL enum)

// The texture coordinates as 16-bit fractions (glTF's normalised unsigned shorts: a 32nd of a texel of a 2048 texture),
// clamped to [0, 1].
std::vector<uint16_t> QuantisedUvs(const TexturedMesh& mesh) {
  std::vector<uint16_t> out;
  out.reserve(2 * mesh.uvs.size());
  for (const Eigen::Vector2f& uv : mesh.uvs) {
    for (int k = 0; k < 2; ++k)
      out.push_back(uv[k] > 0 ? static_cast<uint16_t>(std::lround(std::min(uv[k], 1.0f) * 65535)) : 0);
  }
  return out;
}

// The positions' accessor, with the bounds glTF requires of it.
int AddPositions(tinygltf::Model* model, const TexturedMesh& mesh) {
  const int index = gltf::AddAccessor(model, mesh.positions, mesh.positions.size(), TINYGLTF_TYPE_VEC3,
                                      TINYGLTF_COMPONENT_TYPE_FLOAT);
  gltf::SetBounds(model, index, mesh.positions.empty() ? nullptr : mesh.positions.front().data(), mesh.positions.size(),
                  3);
  return index;
}

// The texture: the JPEG's bytes in the buffer, an unlit material showing them.
int AddMaterial(tinygltf::Model* model, const std::string& texture_jpeg) {
  tinygltf::Image image;
  image.bufferView = gltf::AddView(model, texture_jpeg.data(), texture_jpeg.size(), 0);
  image.mimeType = "image/jpeg";
  model->images.push_back(image);
  tinygltf::Sampler sampler;
  sampler.minFilter = kLinear;
  sampler.magFilter = kLinear;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  model->samplers.push_back(sampler);
  tinygltf::Texture texture;
  texture.source = 0;
  texture.sampler = 0;
  model->textures.push_back(texture);
  tinygltf::Material material;
  material.name = "photo2nerf surface";
  material.pbrMetallicRoughness.baseColorTexture.index = 0;
  material.pbrMetallicRoughness.metallicFactor = 0;
  material.pbrMetallicRoughness.roughnessFactor = 1;
  material.doubleSided = false;
  material.extensions["KHR_materials_unlit"] = tinygltf::Value(tinygltf::Value::Object{});
  model->extensionsUsed.push_back("KHR_materials_unlit");
  model->materials.push_back(material);
  return 0;
}

}  // namespace

std::string TextureJpeg(const TexturedMesh& mesh) {
  OIIO::Filesystem::IOVecOutput memory;
  const std::unique_ptr<OIIO::ImageOutput> output = OIIO::ImageOutput::create("texture.jpg");
  OIIO::ImageSpec spec(mesh.texture_size, mesh.texture_size, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:95");
  spec.attribute("jpeg:subsampling", "4:4:4");
  if (!output || !output->set_ioproxy(&memory) || !output->open("texture.jpg", spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, mesh.texture.data()) || !output->close()) {
    throw std::runtime_error("the texture could not be encoded as JPEG: " +
                             (output ? output->geterror() : OIIO::geterror()));
  }
  return std::string(memory.buffer().begin(), memory.buffer().end());
}

std::string MeshGlbBytes(const TexturedMesh& mesh, const std::string& texture_jpeg, const std::string& generator) {
  tinygltf::Model model = gltf::NewModel(generator);
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.attributes["POSITION"] = AddPositions(&model, mesh);
  const std::vector<uint16_t> uvs = QuantisedUvs(mesh);
  primitive.attributes["TEXCOORD_0"] =
      gltf::AddAccessor(&model, uvs, mesh.uvs.size(), TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                        TINYGLTF_TARGET_ARRAY_BUFFER);
  model.accessors[primitive.attributes["TEXCOORD_0"]].normalized = true;
  primitive.indices = gltf::AddAccessor(&model, mesh.triangles, 3 * mesh.triangles.size(), TINYGLTF_TYPE_SCALAR,
                                        TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  primitive.material = AddMaterial(&model, texture_jpeg);
  return gltf::GlbBytes(std::move(model), std::move(primitive), "surface");
}

}  // namespace p2n
