#include "splat/splat_gltf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "base/gltf_building.h"

namespace p2n {
namespace {

constexpr const char* kExtension = "KHR_gaussian_splatting";

std::string Attribute(const std::string& what) { return std::string(kExtension) + ":" + what; }
std::string ShAttribute(int degree, int n) {
  return Attribute("SH_DEGREE_" + std::to_string(degree) + "_COEF_" + std::to_string(n));
}

// A new accessor of `count` elements of `type` over `values` (floats).
int AddFloats(tinygltf::Model* model, const std::vector<float>& values, int type, size_t count) {
  return gltf::AddAccessor(model, values, count, type, TINYGLTF_COMPONENT_TYPE_FLOAT);
}

// Per splat, `width` values of `g`'s array picked by `value(i, k)`.
template <class Value>
std::vector<float> PerSplat(size_t count, int width, Value value) {
  std::vector<float> out(count * width);
  for (size_t i = 0; i < count; ++i) {
    for (int k = 0; k < width; ++k) out[i * width + k] = value(i, k);
  }
  return out;
}

// The `width` floats per element of accessor `index`, checked against the buffer it reads.
std::vector<float> ReadFloats(const tinygltf::Model& model, int index, size_t count, int width, const std::string& what,
                              const std::string& name) {
  const auto fail = [&](const std::string& why) { throw std::runtime_error(name + ": " + what + ": " + why); };
  if (index < 0 || size_t(index) >= model.accessors.size()) fail("no such accessor");
  const tinygltf::Accessor& accessor = model.accessors[index];
  if (accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT ||
      tinygltf::GetNumComponentsInType(accessor.type) != width)
    fail("not " + std::to_string(width) + " floats an element");
  if (accessor.count != count) fail("not one an element of POSITION");
  if (accessor.bufferView < 0 || size_t(accessor.bufferView) >= model.bufferViews.size()) fail("no buffer view");
  const tinygltf::BufferView& view = model.bufferViews[accessor.bufferView];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) fail("no buffer");
  const size_t element = width * sizeof(float), stride = view.byteStride ? view.byteStride : element;
  const std::vector<unsigned char>& data = model.buffers[view.buffer].data;
  if (stride < element) fail("its stride is shorter than an element");
  if (count == 0) return {};
  // In the view, the view in the buffer; written so that no sum or product can overflow.
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset ||
      accessor.byteOffset > view.byteLength || view.byteLength - accessor.byteOffset < element ||
      count - 1 > (view.byteLength - accessor.byteOffset - element) / stride)
    fail("reaches past its buffer");
  const size_t first = view.byteOffset + accessor.byteOffset;
  std::vector<float> out(count * width);
  for (size_t i = 0; i < count; ++i) std::memcpy(&out[i * width], &data[first + i * stride], width * sizeof(float));
  return out;
}

}  // namespace

std::string SplatGlbBytes(const Gaussians<float>& g, const std::string& generator) {
  tinygltf::Model model = gltf::NewModel(generator);
  model.extensionsUsed.push_back(kExtension);
  const size_t n = g.size();
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_POINTS;
  const std::vector<float> positions = PerSplat(n, 3, [&](size_t i, int k) { return g.positions[3 * i + k]; });
  const int position = primitive.attributes["POSITION"] = AddFloats(&model, positions, TINYGLTF_TYPE_VEC3, n);
  gltf::SetBounds(&model, position, positions.data(), n, 3);
  // For viewers that draw points only: the base colour and the opacity in a byte each.
  std::vector<uint8_t> colours(4 * n);
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 4; ++k) {
      const float value = k < 3 ? float(0.5 + kShC0 * g.sh_dc[3 * i + k]) : Sigmoid(g.opacity_logits[i]);
      colours[4 * i + k] = value > 0 ? static_cast<uint8_t>(std::lround(255 * std::min(value, 1.0f))) : 0;
    }
  }
  const int colour = primitive.attributes["COLOR_0"] =
      gltf::AddAccessor(&model, colours, n, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
  model.accessors[colour].normalized = true;
  primitive.attributes[Attribute("ROTATION")] =
      AddFloats(&model,
                PerSplat(n, 4,
                         [&](size_t i, int k) {
                           const float* q = &g.rotations[4 * i];  // w, x, y, z
                           const float norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
                           return norm > 0 ? q[(k + 1) % 4] / norm : (k == 3 ? 1.0f : 0.0f);
                         }),
                TINYGLTF_TYPE_VEC4, n);
  primitive.attributes[Attribute("SCALE")] = AddFloats(
      &model, PerSplat(n, 3, [&](size_t i, int k) { return g.log_scales[3 * i + k]; }), TINYGLTF_TYPE_VEC3, n);
  primitive.attributes[Attribute("OPACITY")] = AddFloats(
      &model, PerSplat(n, 1, [&](size_t i, int) { return Sigmoid(g.opacity_logits[i]); }), TINYGLTF_TYPE_SCALAR, n);
  primitive.attributes[ShAttribute(0, 0)] =
      AddFloats(&model, PerSplat(n, 3, [&](size_t i, int k) { return g.sh_dc[3 * i + k]; }), TINYGLTF_TYPE_VEC3, n);
  const int rest = g.coefficients() - 1;
  for (int coefficient = 1; coefficient <= rest; ++coefficient) {
    const int degree = static_cast<int>(std::sqrt(double(coefficient)));
    primitive.attributes[ShAttribute(degree, coefficient - degree * degree)] = AddFloats(
        &model, PerSplat(n, 3, [&](size_t i, int k) { return g.sh_rest[3 * (rest * i + coefficient - 1) + k]; }),
        TINYGLTF_TYPE_VEC3, n);
  }
  tinygltf::Value::Object extension;
  extension["kernel"] = tinygltf::Value(std::string("ellipse"));
  extension["colorSpace"] = tinygltf::Value(std::string("srgb_rec709_display"));
  extension["sortingMethod"] = tinygltf::Value(std::string("cameraDistance"));
  extension["projection"] = tinygltf::Value(std::string("perspective"));
  primitive.extensions[kExtension] = tinygltf::Value(extension);
  return gltf::GlbBytes(std::move(model), std::move(primitive), "splats");
}

Gaussians<float> ParseSplatGlb(const std::string& bytes, const std::string& name) {
  tinygltf::Model model;
  std::string error, warning;
  tinygltf::TinyGLTF loader;
  if (bytes.size() > UINT32_MAX ||
      !loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                   static_cast<unsigned>(bytes.size()))) {
    throw std::runtime_error(name + ": not a glTF binary file: " + error);
  }
  const tinygltf::Primitive* splats = nullptr;
  for (const tinygltf::Mesh& mesh : model.meshes) {
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
      if (!splats && primitive.extensions.count(kExtension)) splats = &primitive;
    }
  }
  if (!splats) throw std::runtime_error(name + ": no primitive with " + std::string(kExtension));
  const auto index = [&](const std::string& attribute) {
    const auto found = splats->attributes.find(attribute);
    if (found == splats->attributes.end()) throw std::runtime_error(name + ": no attribute " + attribute);
    return found->second;
  };
  const int position = index("POSITION");
  if (position < 0 || size_t(position) >= model.accessors.size()) throw std::runtime_error(name + ": no POSITION");
  const size_t n = model.accessors[position].count;
  const std::vector<float> positions = ReadFloats(model, position, n, 3, "POSITION", name);  // n within the buffer
  int degree = 0;
  while (degree < kMaxShDegree && splats->attributes.count(ShAttribute(degree + 1, 0))) ++degree;
  Gaussians<float> g;
  g.sh_degree = degree;
  g.Resize(n);
  const auto read = [&](const std::string& attribute, int width) {
    return ReadFloats(model, index(attribute), n, width, attribute, name);
  };
  g.positions = positions;
  g.log_scales = read(Attribute("SCALE"), 3);
  const std::vector<float> rotations = read(Attribute("ROTATION"), 4), opacities = read(Attribute("OPACITY"), 1);
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 4; ++k) g.rotations[4 * i + k] = rotations[4 * i + (k + 3) % 4];  // x y z w -> w x y z
    g.opacity_logits[i] = Logit(std::clamp(opacities[i], 1e-6f, 1 - 1e-6f));
  }
  g.sh_dc = read(ShAttribute(0, 0), 3);
  const int rest = g.coefficients() - 1;
  for (int coefficient = 1; coefficient <= rest; ++coefficient) {
    const int l = static_cast<int>(std::sqrt(double(coefficient)));
    const std::vector<float> values = read(ShAttribute(l, coefficient - l * l), 3);
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) g.sh_rest[3 * (rest * i + coefficient - 1) + k] = values[3 * i + k];
    }
  }
  return g;
}

}  // namespace p2n
