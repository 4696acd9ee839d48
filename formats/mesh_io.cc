#include "formats/mesh_io.h"

#include <cstring>

#include "base/file_util.h"
#include "base/format.h"
#include "base/ply.h"

namespace p2n {

void WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh, const std::vector<std::string>& comments) {
  PlyElement vertices{"vertex", mesh.positions.size(), PlyProperties("float", {"x", "y", "z", "nx", "ny", "nz"})};
  for (const PlyProperty& colour : PlyProperties("uchar", {"red", "green", "blue"}))
    vertices.properties.push_back(colour);
  const PlyElement faces{"face", mesh.triangles.size(), {{"int", "vertex_indices", "uchar"}}};
  std::string data = PlyHeader({vertices, faces}, comments);
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

void WriteTexturedObj(const std::filesystem::path& path, const TexturedMesh& mesh, const std::string& texture_file,
                      const std::vector<std::string>& comments) {
  std::filesystem::path mtl = path;
  mtl.replace_extension(".mtl");
  WriteFileAtomic(mtl, format("# written by photo2nerf\nnewmtl surface\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\n"
                              "map_Kd {}\n",
                              texture_file));
  std::string text = "# written by photo2nerf\n";
  for (const std::string& comment : comments) text += "# " + comment + "\n";
  text += format("mtllib {}\nusemtl surface\n", mtl.filename().string());
  text.reserve(text.size() + mesh.positions.size() * 100 + mesh.triangles.size() * 40);
  for (const Eigen::Vector3f& p : mesh.positions) text += format("v {:.7g} {:.7g} {:.7g}\n", p.x(), p.y(), p.z());
  // OBJ's texture coordinates run up from the image's bottom-left corner.
  for (const Eigen::Vector2f& uv : mesh.uvs) text += format("vt {:.7g} {:.7g}\n", uv.x(), 1 - uv.y());
  for (const Eigen::Vector3f& n : mesh.normals) text += format("vn {:.6g} {:.6g} {:.6g}\n", n.x(), n.y(), n.z());
  for (const auto& t : mesh.triangles) {
    text += format("f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  WriteFileAtomic(path, text);
}

}  // namespace p2n
