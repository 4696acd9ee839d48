#pragma once
// Binary little-endian PLY point clouds with colours (MeshLab, Blender and CloudCompare read them), in the PLY
// container of base/ply.h.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "base/ply.h"

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

}  // namespace p2n
