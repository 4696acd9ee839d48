#include "formats/ply.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr size_t kRecordSize = 3 * sizeof(float) + 3;

// The one element of a point cloud, of `count` points.
PlyElement PointElement(size_t count) {
  PlyElement element{"vertex", count, PlyProperties("float", {"x", "y", "z"})};
  for (const PlyProperty& colour : PlyProperties("uchar", {"red", "green", "blue"}))
    element.properties.push_back(colour);
  return element;
}

bool SameProperties(const std::vector<PlyProperty>& a, const std::vector<PlyProperty>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const PlyProperty& x, const PlyProperty& y) {
    return x.type == y.type && x.name == y.name && x.list_count == y.list_count;
  });
}

}  // namespace

void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points,
              const std::vector<std::string>& comments) {
  std::string data = PlyHeader({PointElement(points.size())}, comments);
  const size_t header = data.size();
  data.resize(header + points.size() * kRecordSize);
  const size_t first = LeadingRecord(points.size(), [&](size_t i) { return points[i].position.x(); });
  for (size_t i = 0; i < points.size(); ++i) {
    const ColouredPoint& point = points[TradedPlace(i, first)];
    char* out = data.data() + header + i * kRecordSize;
    std::memcpy(out, point.position.data(), 3 * sizeof(float));
    std::memcpy(out + 3 * sizeof(float), point.rgb.data(), 3);
  }
  WriteFileAtomic(path, data);
}

std::vector<ColouredPoint> ReadPly(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string data = buffer.str();
  const std::string not_ours = format("'{}' is not a PLY point cloud photo2nerf reads", path.string());
  PlyLayout layout;
  try {
    layout = ReadPlyHeader(data);
  } catch (const std::runtime_error& error) {
    throw UserError(format("{}: {}", not_ours, error.what()));
  }
  if (!layout.BinaryLittleEndian() || layout.elements.size() != 1 || layout.elements[0].name != "vertex" ||
      !SameProperties(layout.elements[0].properties, PointElement(0).properties) ||
      (data.size() - layout.body) / kRecordSize < layout.elements[0].count) {
    throw UserError(not_ours + " (or it is truncated)");
  }
  std::vector<ColouredPoint> points(layout.elements[0].count);
  const char* body = data.data() + layout.body;
  for (size_t i = 0; i < points.size(); ++i) {
    std::memcpy(points[i].position.data(), body + i * kRecordSize, 3 * sizeof(float));
    std::memcpy(points[i].rgb.data(), body + i * kRecordSize + 3 * sizeof(float), 3);
  }
  return points;
}

}  // namespace p2n
