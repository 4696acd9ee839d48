#include "nerf/texture_atlas.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr int kMinSide = 2;  // texels: a square's corners on the centres of its corner texels

// A square of the atlas. Triangles (p, q, r) and (q, p, s) share the edge p-q, the square's diagonal: p at the
// top-left corner, q at the bottom-right, r at the bottom-left and s at the top-right; a triangle without a partner
// (s = kNone) takes the bottom-left half alone.
struct Square {
  uint32_t p, q, r, s = kNone;
  double area = 0;             // of the surface it covers
  int x = 0, y = 0, side = 0;  // its texels: [x, x + side) by [y, y + side)
};

double TriangleArea(const Mesh& mesh, uint32_t a, uint32_t b, uint32_t c) {
  const Eigen::Vector3f& pa = mesh.positions[a];
  return 0.5 * (mesh.positions[b] - pa).cross(mesh.positions[c] - pa).norm();
}

// Triangles paired greedily with an unpaired neighbour across one of their edges.
std::vector<Square> PairTriangles(const Mesh& mesh) {
  const auto key = [](uint32_t a, uint32_t b) { return uint64_t{std::min(a, b)} << 32 | std::max(a, b); };
  std::unordered_multimap<uint64_t, uint32_t> by_edge;
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int e = 0; e < 3; ++e) by_edge.emplace(key(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3]), t);
  }
  std::vector<bool> paired(mesh.triangles.size(), false);
  std::vector<Square> squares;
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (paired[t]) continue;
    paired[t] = true;
    const std::array<uint32_t, 3>& corners = mesh.triangles[t];
    Square square{corners[0], corners[1], corners[2]};
    for (int e = 0; e < 3 && square.s == kNone; ++e) {
      const uint32_t a = corners[e], b = corners[(e + 1) % 3];
      const auto [first, last] = by_edge.equal_range(key(a, b));
      for (auto it = first; it != last; ++it) {
        if (paired[it->second]) continue;
        const std::array<uint32_t, 3>& other = mesh.triangles[it->second];
        uint32_t apex = kNone;
        for (const uint32_t v : other) {
          if (v != a && v != b) apex = v;
        }
        if (apex == kNone) continue;
        paired[it->second] = true;
        square = {a, b, corners[(e + 2) % 3], apex};
        break;
      }
    }
    square.area = TriangleArea(mesh, square.p, square.q, square.r) +
                  (square.s == kNone ? 0 : TriangleArea(mesh, square.q, square.p, square.s));
    squares.push_back(square);
  }
  return squares;
}

// Sides in proportion to the square root of the area covered, `scale` texels a unit, at least kMinSide; packed in
// rows (the squares sorted largest first). False when they overflow the texture.
bool Pack(double scale, int texture_size, std::vector<Square>* squares) {
  int x = 0, y = 0, row_height = 0;
  for (Square& square : *squares) {
    square.side = std::max(kMinSide, static_cast<int>(std::min<double>(texture_size, scale * std::sqrt(square.area))));
    if (x + square.side > texture_size) {
      y += row_height;
      x = 0;
      row_height = 0;
    }
    if (y + square.side > texture_size) return false;
    square.x = x;
    square.y = y;
    x += square.side;
    row_height = std::max(row_height, square.side);
  }
  return true;
}

// The largest scale whose squares fit (bisection).
void PackLargest(int texture_size, size_t triangles, std::vector<Square>* squares) {
  std::sort(squares->begin(), squares->end(), [](const Square& a, const Square& b) { return a.area > b.area; });
  if (!Pack(0, texture_size, squares)) {
    throw UserError(
        format("a texture of {0} x {0} pixels has no room for {1} triangles: raise export.texture_size or "
               "lower export.max_triangles",
               texture_size, triangles));
  }
  double low = 0, high = 1;
  while (high < 1e12 && Pack(high, texture_size, squares)) high *= 2;  // bounded: one square fits at any scale
  for (int i = 0; i < 40; ++i) {
    const double middle = 0.5 * (low + high);
    (Pack(middle, texture_size, squares) ? low : high) = middle;
  }
  Pack(low, texture_size, squares);
}

// Where a texel of a square stands on the surface: its triangle's corners and their weights.
struct TexelPoint {
  std::array<uint32_t, 3> corners;
  Eigen::Vector3f weights;
};

// Texel (i, j) of the square, its centre at (a, b) in [0, 1]^2 between the centres of the corner texels.
TexelPoint Locate(const Square& square, int i, int j) {
  const float a = static_cast<float>(i) / (square.side - 1), b = static_cast<float>(j) / (square.side - 1);
  if (square.s != kNone && a > b) return {{square.p, square.q, square.s}, {1 - a, b, a - b}};
  Eigen::Vector3f weights(1 - b, a, std::max(0.0f, b - a));
  return {{square.p, square.q, square.r}, weights / weights.sum()};
}

}  // namespace

TexturedMesh BakeTexture(const Mesh& mesh, int texture_size, const SurfaceColourFunction& colour) {
  std::vector<Square> squares = PairTriangles(mesh);
  PackLargest(texture_size, mesh.triangles.size(), &squares);
  TexturedMesh out;
  out.texture_size = texture_size;
  out.texture.assign(size_t(3) * texture_size * texture_size, 0);
  std::vector<Eigen::Vector3f> points, normals;
  std::vector<size_t> texels;
  const float size = static_cast<float>(texture_size);
  for (const Square& square : squares) {
    const auto corner = [&](uint32_t v, int i, int j) {
      out.positions.push_back(mesh.positions[v]);
      out.normals.push_back(mesh.normals[v]);
      out.uvs.emplace_back((square.x + i * (square.side - 1) + 0.5f) / size,
                           (square.y + j * (square.side - 1) + 0.5f) / size);
      return static_cast<uint32_t>(out.positions.size() - 1);
    };
    const uint32_t p = corner(square.p, 0, 0), q = corner(square.q, 1, 1), r = corner(square.r, 0, 1);
    out.triangles.push_back({p, q, r});
    if (square.s != kNone) out.triangles.push_back({q, p, corner(square.s, 1, 0)});
    for (int j = 0; j < square.side; ++j) {
      for (int i = 0; i < square.side; ++i) {
        const TexelPoint texel = Locate(square, i, j);
        Eigen::Vector3f point = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::Zero();
        for (int c = 0; c < 3; ++c) {
          point += texel.weights[c] * mesh.positions[texel.corners[c]];
          normal += texel.weights[c] * mesh.normals[texel.corners[c]];
        }
        points.push_back(point);
        normals.push_back(normal.norm() > 0 ? normal.normalized() : mesh.normals[texel.corners[0]]);
        texels.push_back(size_t(square.y + j) * texture_size + square.x + i);
      }
    }
  }
  const std::vector<std::array<uint8_t, 3>> colours = colour(points, normals);
  for (size_t k = 0; k < texels.size(); ++k) {
    std::copy(colours[k].begin(), colours[k].end(), out.texture.begin() + 3 * texels[k]);
  }
  return out;
}

}  // namespace p2n
