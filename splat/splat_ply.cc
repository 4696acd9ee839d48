#include "splat/splat_ply.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "base/file_util.h"
#include "base/ply.h"

namespace p2n {
namespace {

// The property names in file order for `degree`.
std::vector<std::string> PropertyNames(int degree) {
  std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int k = 0; k < 3 * (ShCoefficients(degree) - 1); ++k) names.push_back("f_rest_" + std::to_string(k));
  names.push_back("opacity");
  for (const char* name : {"scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"}) names.push_back(name);
  return names;
}

// Where each property of Gaussian `i` lives in `g` (nullptr for the normals).
template <class G, class Visit>
void ForEachProperty(G& g, size_t i, int degree, Visit&& values) {
  const int rest = ShCoefficients(degree) - 1;
  auto* sh = g.sh_rest.data() + i * 3 * rest;  // none at degree 0
  int at = 0;
  const auto visit = [&](auto& value) { values(value, at++); };
  for (int a = 0; a < 3; ++a) visit(g.positions[3 * i + a]);
  float normal = 0;
  for (int a = 0; a < 3; ++a) visit(normal);
  for (int c = 0; c < 3; ++c) visit(g.sh_dc[3 * i + c]);
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < rest; ++k) visit(sh[3 * k + c]);
  }
  visit(g.opacity_logits[i]);
  for (int a = 0; a < 3; ++a) visit(g.log_scales[3 * i + a]);
  for (int a = 0; a < 4; ++a) visit(g.rotations[4 * i + a]);
}

[[noreturn]] void Fail(const std::string& name, const std::string& problem) {
  throw std::runtime_error("'" + name + "': " + problem + " (expected a binary little-endian 3D Gaussian splat PLY)");
}

// The first vertex element of the PLY file `bytes`, and where the body begins: the vertices' records (an element
// before them would come first in the body: none is read).
PlyElement VertexElement(const std::string& bytes, const std::string& name, size_t* body) {
  PlyLayout layout;
  try {
    layout = ReadPlyHeader(bytes);
  } catch (const std::runtime_error& error) {
    Fail(name, error.what());
  }
  if (!layout.BinaryLittleEndian()) Fail(name, "not binary little-endian");
  *body = layout.body;
  for (const PlyElement& element : layout.elements) {
    if (element.name == "vertex") return element;
  }
  Fail(name, "no vertex element");
}

}  // namespace

std::vector<char> SplatPlyBytes(const Gaussians<float>& gaussians, const std::vector<std::string>& comments) {
  const std::vector<std::string> names = PropertyNames(gaussians.sh_degree);
  const std::string header = PlyHeader({{"vertex", gaussians.size(), PlyProperties("float", names)}}, comments);
  std::vector<char> bytes(header.begin(), header.end());
  const size_t record = names.size() * sizeof(float);
  bytes.resize(header.size() + gaussians.size() * record);
  for (size_t i = 0; i < gaussians.size(); ++i) {
    char* out = bytes.data() + header.size() + i * record;
    ForEachProperty(gaussians, i, gaussians.sh_degree,
                    [&](const float& value, int at) { std::memcpy(out + at * sizeof(float), &value, sizeof(float)); });
  }
  return bytes;
}

void WriteSplatPly(const std::filesystem::path& path, const Gaussians<float>& gaussians,
                   const std::vector<std::string>& comments) {
  WriteBinaryFileAtomic(path, SplatPlyBytes(gaussians, comments));
}

Gaussians<float> ParseSplatPly(const std::string& bytes, const std::string& name) {
  size_t body = 0;
  const PlyElement vertices = VertexElement(bytes, name, &body);
  const size_t count = vertices.count;
  size_t record = 0, rest = 0;
  std::map<std::string, std::pair<size_t, bool>> offsets;  // name -> offset, is double
  for (const PlyProperty& p : vertices.properties) {
    const size_t size = p.list_count.empty() ? PlyTypeSize(p.type) : 0;
    if (size == 0) Fail(name, "property '" + p.name + "' has an unsupported type '" + p.type + "'");
    offsets[p.name] = {record, p.type == "double" || p.type == "float64"};
    record += size;
    if (p.name.rfind("f_rest_", 0) == 0) ++rest;
  }
  int degree = -1;
  for (int d = 0; d <= kMaxShDegree; ++d) {
    if (rest == size_t(3 * (ShCoefficients(d) - 1))) degree = d;
  }
  if (degree < 0) Fail(name, std::to_string(rest) + " f_rest properties (0, 9, 24 or 45 expected)");
  if (record == 0 || count > (bytes.size() - body) / record) {
    Fail(name, "the body is shorter than its " + std::to_string(count) + " vertices");
  }
  const std::vector<std::string> names = PropertyNames(degree);
  std::vector<std::pair<size_t, bool>> where;
  for (const std::string& property : names) {
    const auto found = offsets.find(property);
    if (found == offsets.end() && property[0] != 'n') Fail(name, "no property '" + property + "'");
    where.push_back(found == offsets.end() ? std::pair<size_t, bool>{SIZE_MAX, false} : found->second);
  }
  Gaussians<float> g;
  g.sh_degree = degree;
  g.Resize(count);
  for (size_t i = 0; i < count; ++i) {
    const char* in = bytes.data() + body + i * record;
    ForEachProperty(g, i, degree, [&](float& value, int at) {
      const auto [offset, is_double] = where[at];
      if (offset == SIZE_MAX) return;
      if (is_double) {
        double d;
        std::memcpy(&d, in + offset, sizeof(d));
        value = static_cast<float>(d);
      } else {
        std::memcpy(&value, in + offset, sizeof(float));
      }
    });
  }
  return g;
}

Gaussians<float> ReadSplatPly(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string().insert(0, 1, '\'') + "' cannot be opened");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return ParseSplatPly(buffer.str(), path.string());
}

}  // namespace p2n
