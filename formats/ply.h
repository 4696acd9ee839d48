#pragma once
// Binary little-endian PLY point clouds with colours (MeshLab, Blender and CloudCompare read them).

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace p2n {

struct ColouredPoint {
  Eigen::Vector3f position;
  std::array<uint8_t, 3> rgb;
};

// Throws UserError naming the file when it cannot be written. `comments` go into the header (one line each).
void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points,
              const std::vector<std::string>& comments = {});
// Reads what WritePly writes (vertex x, y, z float; red, green, blue uchar; any comments); UserError naming the
// file otherwise.
std::vector<ColouredPoint> ReadPly(const std::filesystem::path& path);

// PLY header comment lines: "written by photo2nerf", then `comments` (newlines become spaces).
std::string PlyComments(const std::vector<std::string>& comments);

// Which of `count` records to write first: Assimp's PLY reader (5.2, Debian 12's; its issue #5341) skips a line
// end or space right after "end_header\n" even in a binary file, and then reads every record one byte off. The
// writers swap the first record with the first whose first byte (of the float `first_value(i)`) is none of those;
// 0 when that one is, or none is.
template <class FirstValue>
size_t LeadingRecord(size_t count, FirstValue first_value) {
  for (size_t i = 0; i < count; ++i) {
    const float value = first_value(i);
    uint8_t byte;
    std::memcpy(&byte, &value, 1);  // little-endian: the first byte written
    if (byte != 0 && byte != ' ' && (byte < '\t' || byte > '\r')) return i;
  }
  return 0;
}
// With records 0 and `first` trading places: the record at place i of the file, and the place of record i.
inline size_t TradedPlace(size_t i, size_t first) { return i == 0 ? first : i == first ? 0 : i; }

}  // namespace p2n
