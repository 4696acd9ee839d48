// libFuzzer: the PLY writers' round trip. A point cloud and a mesh made from the input, with a header comment
// made from it, are written and read back unchanged: the points by our reader, the mesh by Assimp (an
// independent reader).
#include <assimp/Importer.hpp>
#include <assimp/scene.h>

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "stages/mesh_io.h"
#include "stages/ply.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

bool SameFloat(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

void PointsRoundTrip(const std::string& bytes, const std::vector<std::string>& comments) {
  constexpr size_t kRecord = 3 * sizeof(float) + 3;
  std::vector<p2n::ColouredPoint> points(bytes.size() / kRecord);
  for (size_t i = 0; i < points.size(); ++i) {
    std::memcpy(points[i].position.data(), bytes.data() + i * kRecord, 3 * sizeof(float));
    std::memcpy(points[i].rgb.data(), bytes.data() + i * kRecord + 3 * sizeof(float), 3);
  }
  const auto path = p2n::fuzz::ScratchDir() / "points.ply";
  p2n::WritePly(path, points, comments);
  const std::vector<p2n::ColouredPoint> again = p2n::ReadPly(path);
  if (again.size() != points.size()) std::abort();
  for (size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!SameFloat(again[i].position[k], points[i].position[k]) || again[i].rgb[k] != points[i].rgb[k]) std::abort();
    }
  }
}

// Vertices of 27 bytes (position, normal, colour), then one triangle of 3 bytes (indices modulo the count) each.
void MeshRoundTrip(const std::string& bytes, const std::vector<std::string>& comments) {
  constexpr size_t kVertex = 6 * sizeof(float) + 3;
  const size_t count = bytes.size() / (kVertex + 3);
  if (count == 0) return;
  p2n::Mesh mesh;
  for (size_t i = 0; i < count; ++i) {
    const char* record = bytes.data() + i * kVertex;
    Eigen::Vector3f position, normal;
    std::array<uint8_t, 3> colour;
    std::memcpy(position.data(), record, 3 * sizeof(float));
    std::memcpy(normal.data(), record + 3 * sizeof(float), 3 * sizeof(float));
    std::memcpy(colour.data(), record + 6 * sizeof(float), 3);
    mesh.positions.push_back(position);
    mesh.normals.push_back(normal);
    mesh.colours.push_back(colour);
    const auto* index = reinterpret_cast<const uint8_t*>(bytes.data() + count * kVertex + 3 * i);
    mesh.triangles.push_back({uint32_t(index[0] % count), uint32_t(index[1] % count), uint32_t(index[2] % count)});
  }
  const auto path = p2n::fuzz::ScratchDir() / "mesh.ply";
  p2n::WriteMeshPly(path, mesh, comments);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  if (scene == nullptr || scene->mNumMeshes != 1) std::abort();
  const aiMesh* read = scene->mMeshes[0];
  if (read->mNumVertices != count || read->mNumFaces != count) std::abort();
  for (size_t i = 0; i < count; ++i) {
    const aiFace& face = read->mFaces[i];
    if (face.mNumIndices != 3) std::abort();
    for (int k = 0; k < 3; ++k) {
      if (face.mIndices[k] != mesh.triangles[i][k]) std::abort();
      const float value = mesh.positions[i][k];
      if (std::isfinite(value) && !SameFloat(read->mVertices[i][k], value)) std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> parts = p2n::fuzz::Split(data, size, 3);
  const std::vector<std::string> comments = {parts[0]};
  PointsRoundTrip(parts[1], comments);
  MeshRoundTrip(parts[2], comments);
  return 0;
}
