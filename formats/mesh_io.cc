#include "formats/mesh_io.h"

#include <cstring>

#include "base/file_util.h"
#include "base/format.h"
#include "formats/ply.h"

namespace p2n {

void WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments) {
  std::string data = "ply\nformat binary_little_endian 1.0\n" + PlyComments(comments) +
                     format("element vertex {}\n", mesh.positions.size()) +
                     "property float x\nproperty float y\nproperty float z\n"
                     "property float nx\nproperty float ny\nproperty float nz\n"
                     "property uchar red\nproperty uchar green\nproperty uchar blue\n" +
                     format("element face {}\n", mesh.triangles.size()) +
                     "property list uchar int vertex_indices\nend_header\n";
  constexpr size_t kVertexSize = 6 * sizeof(float) + 3, kFaceSize = 1 + 3 * sizeof(int32_t);
  size_t at = data.size();
  data.resize(at + mesh.positions.size() * kVertexSize + mesh.triangles.size() * kFaceSize);
  const size_t first = LeadingRecord(mesh.positions.size(), [&](size_t v) { return mesh.positions[v].x(); });
  for (size_t place = 0; place < mesh.positions.size(); ++place) {
    const size_t v = TradedPlace(place, first);
    std::memcpy(&data[at], mesh.positions[v].data(), 3 * sizeof(float));
    std::memcpy(&data[at + 3 * sizeof(float)], mesh.normals[v].data(), 3 * sizeof(float));
    std::memcpy(&data[at + 6 * sizeof(float)], mesh.colours[v].data(), 3);
    at += kVertexSize;
  }
  for (const auto& triangle : mesh.triangles) {
    data[at] = 3;
    for (int k = 0; k < 3; ++k) {
      const int32_t index = static_cast<int32_t>(TradedPlace(triangle[k], first));
      std::memcpy(&data[at + 1 + k * sizeof(int32_t)], &index, sizeof(int32_t));
    }
    at += kFaceSize;
  }
  WriteFileAtomic(path, data);
}

void WriteMeshObj(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments) {
  std::string text = "# written by photo2nerf\n";
  for (const std::string& comment : comments) text += "# " + comment + "\n";
  text.reserve(text.size() + mesh.positions.size() * 96 + mesh.triangles.size() * 40);
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3f& p = mesh.positions[v];
    const auto& c = mesh.colours[v];
    text += format("v {:.7g} {:.7g} {:.7g} {:.4g} {:.4g} {:.4g}\n", p.x(), p.y(), p.z(), c[0] / 255.0, c[1] / 255.0,
                   c[2] / 255.0);
  }
  for (const Eigen::Vector3f& n : mesh.normals) text += format("vn {:.6g} {:.6g} {:.6g}\n", n.x(), n.y(), n.z());
  for (const auto& t : mesh.triangles) {
    text += format("f {0}//{0} {1}//{1} {2}//{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  WriteFileAtomic(path, text);
}

}  // namespace p2n
