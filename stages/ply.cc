#include "stages/ply.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"

namespace p2n {
namespace {

// The header without its comment lines (which go after the format line).
constexpr const char* kHeaderFormat =
    "ply\nformat binary_little_endian 1.0\nelement vertex {}\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
constexpr size_t kRecordSize = 3 * sizeof(float) + 3;

std::string WithoutComments(const std::string& header) {
  std::string kept;
  size_t start = 0;
  while (start < header.size()) {
    const size_t end = std::min(header.find('\n', start), header.size() - 1) + 1;
    if (header.compare(start, 8, "comment ") != 0) kept.append(header, start, end - start);
    start = end;
  }
  return kept;
}

}  // namespace

std::string PlyComments(const std::vector<std::string>& comments) {
  std::string text = "comment written by photo2nerf\n";
  for (const std::string& comment : comments) {
    std::string line = comment;
    std::replace(line.begin(), line.end(), '\n', ' ');
    text += "comment " + line + "\n";
  }
  return text;
}

void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points,
              const std::vector<std::string>& comments) {
  std::string data = format(kHeaderFormat, points.size());
  data.insert(data.find("element"), PlyComments(comments));
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
  if (WithoutComments(data.substr(0, body)) != expected || (data.size() - body) / kRecordSize < count) {
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
