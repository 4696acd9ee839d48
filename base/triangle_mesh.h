#pragma once
// Triangle meshes: with normals and vertex colours (what the surface extraction makes), and with a texture.

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

// A mesh whose colour is a texture image: each vertex has texture coordinates, glTF's: (0, 0) the image's top-left
// corner, (1, 1) its bottom-right.
struct TexturedMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Vector2f> uvs;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  int texture_size = 0;                            // the square texture's side, in pixels
  std::vector<uint8_t> texture;                    // RGB, rows from the top
};

}  // namespace p2n
