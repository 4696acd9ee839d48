#include "stages/ply.h"

#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"

namespace p2n {
namespace {

constexpr const char* kHeaderFormat =
    "ply\nformat binary_little_endian 1.0\ncomment written by photo2nerf\nelement vertex {}\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
constexpr size_t kRecordSize = 3 * sizeof(float) + 3;

}  // namespace

void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points) {
  std::string data = format(kHeaderFormat, points.size());
  const size_t header = data.size();
  data.resize(header + points.size() * kRecordSize);
  char* out = data.data() + header;
  for (const ColouredPoint& point : points) {
    std::memcpy(out, point.position.data(), 3 * sizeof(float));
    std::memcpy(out + 3 * sizeof(float), point.rgb.data(), 3);
    out += kRecordSize;
  }
  WriteFileAtomic(path, data);
}

std::vector<ColouredPoint> ReadPly(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string data = buffer.str();
  const size_t end = data.find("end_header\n");
  size_t count = 0;
  const size_t element = data.find("element vertex ");
  if (!in || end == std::string::npos || element == std::string::npos || element > end) {
    throw UserError(format("'{}' is not a PLY point cloud photo2nerf reads", path.string()));
  }
  const char* digits = data.data() + element + 15;
  const auto [end_of_count, error] = std::from_chars(digits, data.data() + end, count);
  if (error != std::errc() || end_of_count == digits) {
    throw UserError(format("'{}' is not a PLY point cloud photo2nerf reads (bad vertex count)", path.string()));
  }
  const std::string expected = format(kHeaderFormat, count);
  const size_t body = end + 11;
  if (data.compare(0, body, expected) != 0 || (data.size() - body) / kRecordSize < count) {
    throw UserError(format("'{}' is not a PLY point cloud photo2nerf reads (or it is truncated)", path.string()));
  }
  std::vector<ColouredPoint> points(count);
  for (size_t i = 0; i < count; ++i) {
    std::memcpy(points[i].position.data(), data.data() + body + i * kRecordSize, 3 * sizeof(float));
    std::memcpy(points[i].rgb.data(), data.data() + body + i * kRecordSize + 3 * sizeof(float), 3);
  }
  return points;
}

}  // namespace p2n
