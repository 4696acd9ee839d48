#include "formats/gltf_io.h"

#include <tiny_gltf.h>

#include <cstring>
#include <sstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"

namespace p2n {
namespace {

constexpr int kLinear = 9729;  // glTF's sampler filter without mipmaps (the GL enum)

// Appends `bytes` to the buffer (4-byte aligned) as a new buffer view; returns its index.
int AddView(tinygltf::Model* model, const void* bytes, size_t size, int target) {
  std::vector<unsigned char>& data = model->buffers[0].data;
  data.resize((data.size() + 3) / 4 * 4);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = size;
  view.target = target;
  data.insert(data.end(), static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + size);
  model->bufferViews.push_back(view);
  return static_cast<int>(model->bufferViews.size() - 1);
}

// An accessor of `count` elements of `type` (TINYGLTF_TYPE_*) over a new view of `values`.
template <class T>
int AddAccessor(tinygltf::Model* model, const std::vector<T>& values, size_t count, int type, int component,
                int target) {
  tinygltf::Accessor accessor;
  accessor.bufferView = AddView(model, values.data(), values.size() * sizeof(T), target);
  accessor.componentType = component;
  accessor.count = count;
  accessor.type = type;
  model->accessors.push_back(accessor);
  return static_cast<int>(model->accessors.size() - 1);
}

// The positions' accessor, with the bounds glTF requires of it.
int AddPositions(tinygltf::Model* model, const TexturedMesh& mesh) {
  Eigen::Vector3f low = Eigen::Vector3f::Constant(0), high = Eigen::Vector3f::Constant(0);
  if (!mesh.positions.empty()) low = high = mesh.positions.front();
  for (const Eigen::Vector3f& p : mesh.positions) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const int index = AddAccessor(model, mesh.positions, mesh.positions.size(), TINYGLTF_TYPE_VEC3,
                                TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
  model->accessors[index].minValues = {low.x(), low.y(), low.z()};
  model->accessors[index].maxValues = {high.x(), high.y(), high.z()};
  return index;
}

// The texture: the JPEG's bytes in the buffer, an unlit material showing them.
int AddMaterial(tinygltf::Model* model, const std::string& texture_jpeg) {
  tinygltf::Image image;
  image.bufferView = AddView(model, texture_jpeg.data(), texture_jpeg.size(), 0);
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

void WriteTextureJpeg(const TexturedMesh& mesh, const std::filesystem::path& path) {
  OIIO::ImageSpec spec(mesh.texture_size, mesh.texture_size, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:95");
  spec.attribute("jpeg:subsampling", "4:4:4");
  const OIIO::ImageBuf image(spec, const_cast<uint8_t*>(mesh.texture.data()));
  if (const std::string error = WriteImage(image, path); !error.empty()) {
    throw UserError(format("{}: {}", path.string(), error));
  }
}

void WriteMeshGlb(const std::filesystem::path& path, const TexturedMesh& mesh, const std::string& texture_jpeg,
                  const std::string& generator) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = generator;
  model.buffers.resize(1);
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.attributes["POSITION"] = AddPositions(&model, mesh);
  primitive.attributes["TEXCOORD_0"] = AddAccessor(&model, mesh.uvs, mesh.uvs.size(), TINYGLTF_TYPE_VEC2,
                                                   TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
  primitive.indices = AddAccessor(&model, mesh.triangles, 3 * mesh.triangles.size(), TINYGLTF_TYPE_SCALAR,
                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  primitive.material = AddMaterial(&model, texture_jpeg);
  tinygltf::Mesh gltf_mesh;
  gltf_mesh.name = "surface";
  gltf_mesh.primitives.push_back(primitive);
  model.meshes.push_back(gltf_mesh);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true)) {
    throw UserError(format("{}: the glTF writer failed", path.string()));
  }
  WriteFileAtomic(path, stream.str());
}

}  // namespace p2n
