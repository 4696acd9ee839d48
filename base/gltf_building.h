#pragma once
// Building a glTF binary (.glb) of one mesh with tinygltf (whoever includes this links TinyGLTF::TinyGLTF): the
// model's one buffer filled view by view, and the file's bytes once the mesh's one primitive is made.

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace p2n::gltf {

// A glTF 2.0 model with one empty buffer, written by `generator`.
inline tinygltf::Model NewModel(const std::string& generator) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = generator;
  model.buffers.resize(1);
  return model;
}

// Appends `size` bytes to the buffer (4-byte aligned) as a new buffer view for `target` (0: none); its index.
inline int AddView(tinygltf::Model* model, const void* bytes, size_t size, int target) {
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

// An accessor of `count` elements of `type` (TINYGLTF_TYPE_*) and `component` (TINYGLTF_COMPONENT_TYPE_*) over a
// new view of `values`; its index.
template <class T>
int AddAccessor(tinygltf::Model* model, const std::vector<T>& values, size_t count, int type, int component,
                int target = TINYGLTF_TARGET_ARRAY_BUFFER) {
  tinygltf::Accessor accessor;
  accessor.bufferView = AddView(model, values.data(), values.size() * sizeof(T), target);
  accessor.componentType = component;
  accessor.count = count;
  accessor.type = type;
  model->accessors.push_back(accessor);
  return static_cast<int>(model->accessors.size() - 1);
}

// Accessor `index`'s bounds (glTF requires them of POSITION): per component of its `width`, the least and the
// greatest finite value of `values` (0 where there is none; JSON holds no infinity or NaN).
inline void SetBounds(tinygltf::Model* model, int index, const float* values, size_t count, int width) {
  std::vector<double> low(width, INFINITY), high(width, -INFINITY);
  for (size_t i = 0; i < count * width; ++i) {
    if (!std::isfinite(values[i])) continue;
    low[i % width] = std::min<double>(low[i % width], values[i]);
    high[i % width] = std::max<double>(high[i % width], values[i]);
  }
  for (int k = 0; k < width; ++k) {
    if (low[k] > high[k]) low[k] = high[k] = 0;
  }
  model->accessors[index].minValues = low;
  model->accessors[index].maxValues = high;
}

// The .glb file's bytes: `model` with `primitive` as its one mesh, called `name`, in its one scene.
// std::runtime_error when the writer fails.
inline std::string GlbBytes(tinygltf::Model model, tinygltf::Primitive primitive, const std::string& name) {
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(std::move(primitive));
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream stream;
  if (!tinygltf::TinyGLTF().WriteGltfSceneToStream(&model, stream, false, true)) {
    throw std::runtime_error("the glTF writer failed");
  }
  return stream.str();
}

}  // namespace p2n::gltf
