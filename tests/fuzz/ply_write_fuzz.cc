// libFuzzer: the PLY writers' round trip. A point cloud and a mesh made from the input, with a header comment
// made from it, are written and read back unchanged: the points by our reader, the mesh by splitting the file
// into the header lines a PLY reader sees and the binary records, in the writers' order: the first record trades
// places with the first whose first byte Assimp cannot take for a line end or space (p2n::LeadingRecord; Assimp
// was the mesh's reader here first, and its faces came back empty for some vertex values: that bug).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "formats/mesh_io.h"
#include "formats/ply.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "round trip failed: %s\n", what);
  std::abort();
}

bool SameFloat(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// Whether Assimp may skip this byte right after the header: a line end, a space or a NUL.
bool Skippable(char byte) { return byte == 0 || byte == ' ' || (byte >= '\t' && byte <= '\r'); }

// The first record written begins with a byte Assimp reads as data whenever one of the `count` records of
// `stride` bytes in `records` does.
void CheckLeadingByte(const char* records, size_t count, size_t stride, const char* written) {
  for (size_t i = 0; i < count; ++i) {
    if (!Skippable(records[i * stride])) {
      if (Skippable(written[0])) Fail("a skippable first byte");
      return;
    }
  }
}

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
  if (again.size() != points.size()) Fail("point count");
  const size_t first = p2n::LeadingRecord(points.size(), [&](size_t i) { return points[i].position.x(); });
  for (size_t i = 0; i < points.size(); ++i) {
    const p2n::ColouredPoint& point = points[p2n::TradedPlace(i, first)];
    for (int k = 0; k < 3; ++k) {
      if (!SameFloat(again[i].position[k], point.position[k]) || again[i].rgb[k] != point.rgb[k]) Fail("point");
    }
  }
  if (!again.empty()) {
    float x = again[0].position.x();
    char leading;
    std::memcpy(&leading, &x, 1);
    CheckLeadingByte(bytes.data(), points.size(), kRecord, &leading);
  }
}

// The mesh file split into its header lines (comments left out) and its body, as a PLY reader sees it.
std::pair<std::string, std::string> HeaderAndBody(const std::string& file) {
  std::string header;
  size_t at = 0;
  while (true) {
    const size_t newline = file.find('\n', at);
    if (newline == std::string::npos) Fail("no end_header line");
    const std::string line = file.substr(at, newline - at);
    at = newline + 1;
    if (line.rfind("comment ", 0) == 0) continue;
    header += line + "\n";
    if (line == "end_header") return {header, file.substr(at)};
  }
}

// Vertices of 27 bytes (position, normal, colour), then one triangle of 3 bytes (indices modulo the count) each.
// The file must hold the header a PLY reader expects (whatever the comments hold) and every value unchanged.
void MeshRoundTrip(const std::string& bytes, const std::vector<std::string>& comments) {
  constexpr size_t kVertex = 6 * sizeof(float) + 3, kFace = 1 + 3 * sizeof(int32_t);
  const size_t count = bytes.size() / (kVertex + 3);
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
  std::ifstream in(path, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto [header, body] = HeaderAndBody(file);
  const std::string expected = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(count) +
                               "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
                               "float ny\nproperty float nz\n"
                               "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face " +
                               std::to_string(count) + "\nproperty list uchar int vertex_indices\nend_header\n";
  if (header != expected) Fail("header");
  if (body.size() != count * (kVertex + kFace)) Fail("body size");
  CheckLeadingByte(bytes.data(), count, kVertex, body.data());
  const size_t first = p2n::LeadingRecord(count, [&](size_t v) { return mesh.positions[v].x(); });
  for (size_t i = 0; i < count; ++i) {
    if (std::memcmp(body.data() + i * kVertex, bytes.data() + p2n::TradedPlace(i, first) * kVertex, kVertex) != 0) {
      Fail("vertex");
    }
    const char* face = body.data() + count * kVertex + i * kFace;
    int32_t indices[3];
    std::memcpy(indices, face + 1, sizeof(indices));
    for (int k = 0; k < 3; ++k) {
      if (face[0] != 3 || indices[k] != static_cast<int32_t>(p2n::TradedPlace(mesh.triangles[i][k], first)))
        Fail("face");
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
