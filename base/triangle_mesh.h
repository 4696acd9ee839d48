#pragma once
// A triangle mesh with normals and vertex colours: what the surface extraction makes and the mesh files hold.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace p2n {

struct Mesh {
  std::vector<Eigen::Vector3f> positions;  // world units of the normalised frame
  std::vector<Eigen::Vector3f> normals;    // unit, pointing out of the surface (down the density gradient)
  std::vector<std::array<uint8_t, 3>> colours;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

}  // namespace p2n
