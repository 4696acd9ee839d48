#pragma once
// Binary little-endian PLY point clouds with colours (MeshLab, Blender and CloudCompare read them).

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace p2n {

struct ColouredPoint {
  Eigen::Vector3f position;
  std::array<uint8_t, 3> rgb;
};

// Throws UserError naming the file when it cannot be written.
void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points);
// Reads what WritePly writes (vertex x, y, z float; red, green, blue uchar); UserError naming the file otherwise.
std::vector<ColouredPoint> ReadPly(const std::filesystem::path& path);

}  // namespace p2n
