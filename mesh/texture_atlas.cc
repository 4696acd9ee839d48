#include "mesh/texture_atlas.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr int kGutter = 2;  // texels round each chart repeating its edge
// A chart's triangles face within 45 degrees of its first one; where a rough surface makes too many charts to fit,
// within 73 and then 90 degrees (still never turned over when laid flat).
constexpr float kChartCosines[] = {0.7f, 0.3f, 0.0f};
constexpr size_t kMaxChartTriangles = 4096;

// Connected triangles laid flat: `axes` rows project a point onto the chart's plane.
struct Chart {
  std::vector<uint32_t> triangles;
  Eigen::Matrix<float, 2, 3> axes;
  Eigen::Vector2f low, high;                // the projected bounds
  int x = 0, y = 0, width = 0, height = 0;  // its texels, the gutter included
};

Eigen::Vector3f FaceNormal(const Mesh& mesh, const std::array<uint32_t, 3>& t) {
  const Eigen::Vector3f n =
      (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
  return n.norm() > 0 ? n.normalized() : Eigen::Vector3f::UnitZ();
}

// Each triangle's neighbours across its edges (shared by exactly two triangles).
std::vector<std::array<uint32_t, 3>> Neighbours(const Mesh& mesh) {
  constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  const auto key = [](uint32_t a, uint32_t b) { return uint64_t{std::min(a, b)} << 32 | std::max(a, b); };
  std::unordered_map<uint64_t, std::vector<uint32_t>> by_edge;
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int e = 0; e < 3; ++e) by_edge[key(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3])].push_back(t);
  }
  std::vector<std::array<uint32_t, 3>> neighbours(mesh.triangles.size(), {kNone, kNone, kNone});
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int e = 0; e < 3; ++e) {
      const std::vector<uint32_t>& sharing = by_edge[key(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3])];
      if (sharing.size() == 2) neighbours[t][e] = sharing[0] == t ? sharing[1] : sharing[0];
    }
  }
  return neighbours;
}

// What growing charts asks of the mesh, whatever the cosine: each triangle's neighbours and unit normal.
struct Adjacency {
  std::vector<std::array<uint32_t, 3>> neighbours;
  std::vector<Eigen::Vector3f> normals;
};

// Charts grown breadth-first from the first triangle not yet in one.
std::vector<Chart> GrowCharts(const Mesh& mesh, const Adjacency& adjacency, float min_cosine) {
  std::vector<bool> taken(mesh.triangles.size(), false);
  std::vector<Chart> charts;
  for (uint32_t seed = 0; seed < mesh.triangles.size(); ++seed) {
    if (taken[seed]) continue;
    Chart& chart = charts.emplace_back();
    const Eigen::Vector3f& normal = adjacency.normals[seed];
    taken[seed] = true;
    chart.triangles.push_back(seed);
    for (size_t next = 0; next < chart.triangles.size() && chart.triangles.size() < kMaxChartTriangles; ++next) {
      for (const uint32_t n : adjacency.neighbours[chart.triangles[next]]) {
        if (n >= taken.size() || taken[n] || adjacency.normals[n].dot(normal) < min_cosine) continue;
        taken[n] = true;
        chart.triangles.push_back(n);
      }
    }
    const Eigen::Vector3f u = normal.unitOrthogonal();
    chart.axes.row(0) = u.transpose();
    chart.axes.row(1) = normal.cross(u).transpose();
    chart.low = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
    chart.high = -chart.low;
    for (const uint32_t t : chart.triangles) {
      for (const uint32_t v : mesh.triangles[t]) {
        const Eigen::Vector2f p = chart.axes * mesh.positions[v];
        chart.low = chart.low.cwiseMin(p);
        chart.high = chart.high.cwiseMax(p);
      }
    }
  }
  return charts;
}

// The charts' rectangles at `scale` texels a unit packed in rows, tallest first; false when they overflow.
bool Pack(double scale, int texture_size, std::vector<Chart>* charts) {
  int x = 0, y = 0, row_height = 0;
  for (Chart& chart : *charts) {
    const Eigen::Vector2f extent = chart.high - chart.low;
    chart.width = static_cast<int>(std::ceil(scale * extent.x())) + 1 + 2 * kGutter;
    chart.height = static_cast<int>(std::ceil(scale * extent.y())) + 1 + 2 * kGutter;
    if (chart.width > texture_size || chart.height > texture_size) return false;
    if (x + chart.width > texture_size) {
      y += row_height;
      x = 0;
      row_height = 0;
    }
    if (y + chart.height > texture_size) return false;
    chart.x = x;
    chart.y = y;
    x += chart.width;
    row_height = std::max(row_height, chart.height);
  }
  return true;
}

// The largest scale at which the charts fit (bisection); false when they do not fit at any.
bool PackLargest(int texture_size, std::vector<Chart>* charts, double* scale) {
  std::sort(charts->begin(), charts->end(),
            [](const Chart& a, const Chart& b) { return a.high.y() - a.low.y() > b.high.y() - b.low.y(); });
  if (!Pack(0, texture_size, charts)) return false;
  double low = 0, high = 1;
  while (high < 1e12 && Pack(high, texture_size, charts)) high *= 2;
  for (int i = 0; i < 40; ++i) {
    const double middle = 0.5 * (low + high);
    (Pack(middle, texture_size, charts) ? low : high) = middle;
  }
  Pack(low, texture_size, charts);
  *scale = low;
  return true;
}

// The mesh's charts, packed at `*scale`: the strictest of kChartCosines that fits. UserError when none does.
std::vector<Chart> ChartsThatFit(const Mesh& mesh, int texture_size, double* scale) {
  Adjacency adjacency{Neighbours(mesh), {}};
  for (const auto& t : mesh.triangles) adjacency.normals.push_back(FaceNormal(mesh, t));
  std::vector<Chart> charts;
  for (const float cosine : kChartCosines) {
    charts = GrowCharts(mesh, adjacency, cosine);
    if (PackLargest(texture_size, &charts, scale)) return charts;
  }
  throw UserError(
      format("a texture of {0} x {0} pixels has no room for the mesh's {1} charts: raise "
             "export.texture_size or lower export.max_triangles",
             texture_size, charts.size()));
}

// Texels whose centres a triangle covers: their index in the texture, the surface point and normal there.
struct Texels {
  std::vector<size_t> index;
  std::vector<Eigen::Vector3f> points, normals;
};

// The barycentric weights of the point of triangle `uv` nearest `p`, and its distance from `p`.
std::pair<Eigen::Vector3f, float> Nearest(const std::array<Eigen::Vector2f, 3>& uv, const Eigen::Vector2f& p) {
  const auto cross = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) { return a.x() * b.y() - a.y() * b.x(); };
  const float area = cross(uv[1] - uv[0], uv[2] - uv[0]);
  if (area != 0) {
    const Eigen::Vector3f w(cross(uv[1] - p, uv[2] - p) / area, cross(uv[2] - p, uv[0] - p) / area,
                            cross(uv[0] - p, uv[1] - p) / area);
    if (w.minCoeff() >= 0) return {w, 0.0f};
  }
  std::pair<Eigen::Vector3f, float> best{Eigen::Vector3f(1, 0, 0), std::numeric_limits<float>::max()};
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector2f& a = uv[e];
    const Eigen::Vector2f edge = uv[(e + 1) % 3] - a;
    const float along = edge.squaredNorm() > 0 ? std::clamp((p - a).dot(edge) / edge.squaredNorm(), 0.0f, 1.0f) : 0;
    const float distance = (a + along * edge - p).norm();
    if (distance >= best.second) continue;
    best.first.setZero();
    best.first[e] = 1 - along;
    best.first[(e + 1) % 3] = along;
    best.second = distance;
  }
  return best;
}

// Adds the texels that triangle `t` of the mesh, at texture coordinates `uv` (in texels), covers: those it
// overlaps (their centres within kCover of it), each standing for the triangle's point nearest its centre.
void Rasterise(const Mesh& mesh, const std::array<uint32_t, 3>& t, const std::array<Eigen::Vector2f, 3>& uv,
               int texture_size, std::vector<bool>* covered, Texels* texels) {
  constexpr float kCover = 0.75f;  // texels: a little over half a texel's diagonal
  const Eigen::Vector2f low = uv[0].cwiseMin(uv[1]).cwiseMin(uv[2]), high = uv[0].cwiseMax(uv[1]).cwiseMax(uv[2]);
  for (int y = std::max(0, int(low.y()) - 1); y <= std::min(texture_size - 1, int(high.y()) + 1); ++y) {
    for (int x = std::max(0, int(low.x()) - 1); x <= std::min(texture_size - 1, int(high.x()) + 1); ++x) {
      const size_t i = size_t(y) * texture_size + x;
      if ((*covered)[i]) continue;
      const auto [w, distance] = Nearest(uv, Eigen::Vector2f(x + 0.5f, y + 0.5f));
      if (distance > kCover) continue;
      (*covered)[i] = true;
      Eigen::Vector3f point = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::Zero();
      for (int c = 0; c < 3; ++c) {
        point += w[c] * mesh.positions[t[c]];
        normal += w[c] * mesh.normals[t[c]];
      }
      texels->index.push_back(i);
      texels->points.push_back(point);
      texels->normals.push_back(normal.norm() > 0 ? normal.normalized() : mesh.normals[t[0]]);
    }
  }
}

// Texels no triangle covers take the mean of their covered neighbours, kGutter rings out from each chart.
void Dilate(int texture_size, std::vector<bool> covered, std::vector<uint8_t>* texture) {
  for (int ring = 0; ring < kGutter; ++ring) {
    std::vector<size_t> filled;
    for (int y = 0; y < texture_size; ++y) {
      for (int x = 0; x < texture_size; ++x) {
        const size_t i = size_t(y) * texture_size + x;
        if (covered[i]) continue;
        int sum[3] = {0, 0, 0}, count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= texture_size || ny >= texture_size) continue;
            const size_t j = size_t(ny) * texture_size + nx;
            if (!covered[j]) continue;
            for (int c = 0; c < 3; ++c) sum[c] += (*texture)[3 * j + c];
            ++count;
          }
        }
        if (count == 0) continue;
        for (int c = 0; c < 3; ++c) (*texture)[3 * i + c] = static_cast<uint8_t>((sum[c] + count / 2) / count);
        filled.push_back(i);
      }
    }
    for (const size_t i : filled) covered[i] = true;
  }
}

}  // namespace

TexturedMesh BakeTexture(const Mesh& mesh, int texture_size, const SurfaceColourFunction& colour) {
  double scale = 0;
  const std::vector<Chart> charts = ChartsThatFit(mesh, texture_size, &scale);
  TexturedMesh out;
  out.texture_size = texture_size;
  out.texture.assign(size_t(3) * texture_size * texture_size, 0);
  std::vector<bool> covered(size_t(texture_size) * texture_size, false);
  Texels texels;
  const float size = static_cast<float>(texture_size);
  for (const Chart& chart : charts) {
    std::unordered_map<uint32_t, uint32_t> vertex;  // the mesh's vertex -> the chart's copy
    const Eigen::Vector2f origin(chart.x + kGutter + 0.5f, chart.y + kGutter + 0.5f);
    for (const uint32_t t : chart.triangles) {
      std::array<uint32_t, 3> corners;
      std::array<Eigen::Vector2f, 3> uv;
      for (int c = 0; c < 3; ++c) {
        const uint32_t v = mesh.triangles[t][c];
        uv[c] = origin + static_cast<float>(scale) * (chart.axes * mesh.positions[v] - chart.low);
        const auto [it, added] = vertex.emplace(v, static_cast<uint32_t>(out.positions.size()));
        if (added) {
          out.positions.push_back(mesh.positions[v]);
          out.normals.push_back(mesh.normals[v]);
          out.uvs.push_back(uv[c] / size);
        }
        corners[c] = it->second;
      }
      out.triangles.push_back(corners);
      Rasterise(mesh, mesh.triangles[t], uv, texture_size, &covered, &texels);
    }
  }
  const std::vector<std::array<uint8_t, 3>> colours = colour(texels.points, texels.normals);
  for (size_t k = 0; k < texels.index.size(); ++k) {
    std::copy(colours[k].begin(), colours[k].end(), out.texture.begin() + 3 * texels.index[k]);
  }
  Dilate(texture_size, std::move(covered), &out.texture);
  return out;
}

}  // namespace p2n
