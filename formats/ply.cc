#include "formats/ply.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace {

// The header without its comment lines (which go after the format line).
constexpr const char* kHeaderFormat =
    "ply\nformat binary_little_endian 1.0\nelement vertex {}\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
constexpr size_t kRecordSize = 3 * sizeof(float) + 3;

}  // namespace

std::string PlyComments(const std::vector<std::string>& comments) {
  std::string text = "comment written by photo2nerf\n";
  for (const std::string& comment : comments) {
    std::string line = comment;
    // One line each, whatever it holds: other readers end a line at '\r' too.
    std::replace_if(
        line.begin(), line.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
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
  // The header line by line, comments left out (they may hold any text, "end_header" too).
  std::string header;
  size_t at = 0, body = std::string::npos;
  while (body == std::string::npos) {
    const size_t newline = data.find('\n', at);
    if (!in || newline == std::string::npos) {
      throw UserError(format("'{}' is not a PLY point cloud photo2nerf reads", path.string()));
    }
    const std::string_view line(data.data() + at, newline - at);
    at = newline + 1;
    if (line.starts_with("comment ")) continue;
    header.append(line).push_back('\n');
    if (line == "end_header") body = at;
  }
  constexpr std::string_view kCountAt = "ply\nformat binary_little_endian 1.0\nelement vertex ";
  size_t count = 0;
  const char* digits = header.data() + std::min(kCountAt.size(), header.size());
  const auto [end_of_count, error] = std::from_chars(digits, header.data() + header.size(), count);
  if (!header.starts_with(kCountAt) || error != std::errc() || end_of_count == digits ||
      header != format(kHeaderFormat, count) || (data.size() - body) / kRecordSize < count) {
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
