#include "splat/field_init.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <tbb/parallel_for.h>

#include "nerf/rays.h"
#include "nerf/renderer.h"

namespace p2n {
namespace {

constexpr double kTangentSigma = 0.5;        // cells
constexpr double kNormalSigma = 0.05;        // cells
constexpr double kMinNormalAgreement = 0.5;  // length of the cell's mean unit normal
constexpr double kOpacityShare = 0.8;        // of the field's opacity
constexpr double kDepthTolerance = 0.03;     // relative: two views agree on a point's depth
constexpr double kSparseOpacity = 0.1;       // 3D Gaussian Splatting's first opacity

struct CellKey {
  int level;
  int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

struct CellKeyHash {
  size_t operator()(const CellKey& k) const {
    uint64_t h = static_cast<uint64_t>(k.level) * 0x9E3779B97F4A7C15ull;
    for (const int64_t v : {k.x, k.y, k.z}) h = (h ^ static_cast<uint64_t>(v)) * 0xBF58476D1CE4E5B9ull + (h >> 29);
    return static_cast<size_t>(h);
  }
};

struct Cell {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double opacity = 0;
  int count = 0;
};

// Cells of side 2^level, level the rounded log2 of (footprint · spread); keyed by level and integer coordinates.
std::unordered_map<CellKey, Cell, CellKeyHash> Pool(const std::vector<SurfacePoint>& points, double spread) {
  std::unordered_map<CellKey, Cell, CellKeyHash> cells;
  for (const SurfacePoint& p : points) {
    const int level = static_cast<int>(std::lround(std::log2(std::max(p.footprint * spread, 1e-9))));
    const double side = std::ldexp(1.0, level);
    const CellKey key{level, static_cast<int64_t>(std::floor(p.position.x() / side)),
                      static_cast<int64_t>(std::floor(p.position.y() / side)),
                      static_cast<int64_t>(std::floor(p.position.z() / side))};
    Cell& cell = cells[key];
    cell.position += p.position;
    cell.rgb += p.rgb.cast<double>();
    cell.normal += p.normal.cast<double>();
    cell.opacity += p.opacity;
    ++cell.count;
  }
  return cells;
}

}  // namespace

Gaussians<float> GaussiansFromPoints(const std::vector<SurfacePoint>& points, size_t max_gaussians, int sh_degree) {
  double spread = 1;
  std::unordered_map<CellKey, Cell, CellKeyHash> cells = Pool(points, spread);
  while (cells.size() > max_gaussians) cells = Pool(points, spread *= std::sqrt(2.0));  // half the cells a step
  Gaussians<float> g;
  g.sh_degree = sh_degree;
  g.Resize(cells.size());
  size_t i = 0;
  for (const auto& [key, cell] : cells) {
    const Eigen::Vector3d mean = cell.position / cell.count;
    const double side = std::ldexp(1.0, key.level);
    // Along the surface, σ of kTangentSigma cells: neighbouring discs overlap into an even cover; across it, thin.
    // Where the cell's normals disagree (an edge, a thin part seen from both sides), a ball.
    const Eigen::Vector3d normal = cell.normal / cell.count;
    const bool flat = normal.norm() > kMinNormalAgreement;
    const Eigen::Quaterniond rotation =
        flat ? Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), normal) : Eigen::Quaterniond::Identity();
    const double tangent = kTangentSigma * side, across = flat ? kNormalSigma * side : tangent;
    for (int a = 0; a < 3; ++a) {
      g.positions[3 * i + a] = static_cast<float>(mean[a]);
      g.log_scales[3 * i + a] = static_cast<float>(std::log(a == 2 ? across : tangent));
      g.sh_dc[3 * i + a] = static_cast<float>((cell.rgb[a] / cell.count - 0.5) / kShC0);
    }
    const double q[4] = {rotation.w(), rotation.x(), rotation.y(), rotation.z()};
    for (int a = 0; a < 4; ++a) g.rotations[4 * i + a] = static_cast<float>(q[a]);
    const double opacity = std::clamp(kOpacityShare * cell.opacity / cell.count, 0.01, 0.99);
    g.opacity_logits[i] = static_cast<float>(Logit(opacity));
    ++i;
  }
  return g;
}

namespace {

// The root mean square distance of each point to its three nearest others, searched in a grid of about one point
// a cell, shell by shell (up to kMaxShells cells away; the grid's cell where none is nearer).
std::vector<double> NeighbourDistances(const std::vector<Eigen::Vector3d>& points) {
  constexpr int kNeighbours = 3, kMaxShells = 4;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : points) box.extend(p);
  const Eigen::Vector3d size = box.sizes().cwiseMax(1e-9);
  const double cell = std::max(std::cbrt(size.prod() / static_cast<double>(points.size())), size.maxCoeff() * 1e-4);
  const auto key = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d c = ((p - box.min()) / cell).array().floor();
    return CellKey{0, static_cast<int64_t>(c.x()), static_cast<int64_t>(c.y()), static_cast<int64_t>(c.z())};
  };
  std::unordered_map<CellKey, std::vector<size_t>, CellKeyHash> grid;
  for (size_t i = 0; i < points.size(); ++i) grid[key(points[i])].push_back(i);
  std::vector<double> distances(points.size(), cell);
  tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
    const CellKey home = key(points[i]);
    std::vector<double> nearest;  // squared, the kNeighbours smallest so far
    for (int r = 0; r <= kMaxShells; ++r) {
      for (int64_t x = -r; x <= r; ++x) {
        for (int64_t y = -r; y <= r; ++y) {
          for (int64_t z = -r; z <= r; ++z) {
            if (std::max({std::abs(x), std::abs(y), std::abs(z)}) != r) continue;  // this shell only
            const auto found = grid.find({0, home.x + x, home.y + y, home.z + z});
            if (found == grid.end()) continue;
            for (const size_t j : found->second) {
              if (j != i) nearest.push_back((points[j] - points[i]).squaredNorm());
            }
          }
        }
      }
      std::sort(nearest.begin(), nearest.end());
      if (nearest.size() > kNeighbours) nearest.resize(kNeighbours);
      // Points beyond shell r are at least r cells away: done when the k-th nearest is closer than that.
      if (nearest.size() == kNeighbours && nearest.back() <= std::pow(r * cell, 2)) break;
    }
    if (!nearest.empty()) {
      double sum = 0;
      for (const double d : nearest) sum += d;
      distances[i] = std::max(std::sqrt(sum / static_cast<double>(nearest.size())), cell * 1e-3);
    }
  });
  return distances;
}

}  // namespace

Gaussians<float> GaussiansFromSparsePoints(const std::vector<Eigen::Vector3d>& points,
                                           const std::vector<Eigen::Vector3f>& rgb, size_t max_gaussians,
                                           int sh_degree) {
  if (points.empty()) return GaussiansFromPoints({}, max_gaussians, sh_degree);
  const std::vector<double> distances = NeighbourDistances(points);
  std::vector<SurfacePoint> surface(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    // A cell of about the neighbour distance: its Gaussian's sigma is kTangentSigma of it.
    surface[i] = {points[i], rgb[i], Eigen::Vector3f::Zero(), static_cast<float>(kSparseOpacity / kOpacityShare),
                  distances[i]};
  }
  return GaussiansFromPoints(surface, max_gaussians, sh_degree);
}

namespace {

// The training views rendered small, with their median depths.
struct DepthViews {
  const std::vector<PinholeCamera>& cameras;
  const std::vector<RenderedView>& renders;

  // How many views other than `self` see `p` at its distance from them (within kDepthTolerance of it), counting
  // up to `enough`: a point that only its own view puts there is a floater of that view's depth, not a surface.
  int Support(const Eigen::Vector3d& p, size_t self, int enough) const {
    int support = 0;
    for (size_t j = 0; j < cameras.size() && support < enough; ++j) {
      if (j == self) continue;
      double z = 0;
      const Eigen::Vector2d pixel = Project(cameras[j], p, &z);
      const int x = static_cast<int>(std::floor(pixel.x())), y = static_cast<int>(std::floor(pixel.y()));
      if (!(z > 0) || x < 0 || y < 0 || x >= cameras[j].width || y >= cameras[j].height) continue;
      const size_t i = size_t(y) * cameras[j].width + x;
      if (renders[j].opacity.pixels[i] <= 0) continue;
      const double distance = (p - cameras[j].world_from_cam.topRightCorner<3, 1>()).norm();
      if (std::abs(renders[j].depth.pixels[i] - distance) <= kDepthTolerance * distance) ++support;
    }
    return support;
  }
};

// The points of view `v`: pixels at least `min_opacity` opaque, at their median depth, seen there by at least
// `min_views` views (their own included), with the surface's colour and the depth map's normal where the
// neighbouring pixels lie on the same surface.
void AddViewPoints(const NerfModel& model, const DepthViews& views, size_t v, double min_opacity, int min_views,
                   std::vector<SurfacePoint>* points) {
  const PinholeCamera& camera = views.cameras[v];
  const RenderedView& rendered = views.renders[v];
  const int w = camera.width, h = camera.height;
  std::vector<Eigen::Vector3d> position(size_t(w) * h, Eigen::Vector3d::Constant(NAN));
  std::vector<Eigen::Vector3d> origin(position.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!(rendered.opacity.pixels[i] >= min_opacity)) continue;
      const Ray ray = CameraRay(camera, x + 0.5, y + 0.5);
      position[i] = ray.origin + double(rendered.depth.pixels[i]) * ray.direction;
      origin[i] = ray.origin;
    }
  }
  // A neighbour's point if it is on the same surface: within kMaxStep footprints of depth.
  constexpr double kMaxStep = 4;
  const auto neighbour = [&](int x, int y, size_t i, double footprint) -> const Eigen::Vector3d* {
    if (x < 0 || y < 0 || x >= w || y >= h) return nullptr;
    const Eigen::Vector3d& p = position[size_t(y) * w + x];
    if (!p.allFinite()) return nullptr;
    return std::abs(rendered.depth.pixels[size_t(y) * w + x] - rendered.depth.pixels[i]) <= kMaxStep * footprint
               ? &p
               : nullptr;
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!position[i].allFinite()) continue;
      const float opacity = rendered.opacity.pixels[i];
      if (views.Support(position[i], v, min_views - 1) < min_views - 1) continue;
      SurfacePoint point;
      point.position = position[i];
      point.footprint = rendered.depth.pixels[i] / camera.fx;  // about: the ray's length over the focal length
      for (int c = 0; c < 3; ++c) {                            // the render less the background seen through it
        const float surface = (rendered.rgb.pixels[3 * i + c] - (1 - opacity) * model.background[c]) / opacity;
        point.rgb[c] = std::clamp(surface, 0.0f, 1.0f);
      }
      point.opacity = opacity;
      const Eigen::Vector3d *left = neighbour(x - 1, y, i, point.footprint),
                            *right = neighbour(x + 1, y, i, point.footprint),
                            *up = neighbour(x, y - 1, i, point.footprint),
                            *down = neighbour(x, y + 1, i, point.footprint);
      if ((left || right) && (up || down)) {
        const Eigen::Vector3d across = (right ? *right : position[i]) - (left ? *left : position[i]);
        const Eigen::Vector3d along = (down ? *down : position[i]) - (up ? *up : position[i]);
        Eigen::Vector3d normal = across.cross(along).normalized();
        if (normal.dot(origin[i] - position[i]) < 0) normal = -normal;
        if (normal.allFinite()) point.normal = normal.cast<float>();
      }
      points->push_back(point);
    }
  }
}

}  // namespace

Gaussians<float> GaussiansFromRenders(const NerfModel& model, const std::vector<PinholeCamera>& cameras,
                                      const std::vector<RenderedView>& renders, const FieldInitOptions& options) {
  const DepthViews depth_views{cameras, renders};
  std::vector<std::vector<SurfacePoint>> per_view(cameras.size());
  tbb::parallel_for(size_t(0), cameras.size(), [&](size_t v) {
    AddViewPoints(model, depth_views, v, options.min_opacity, options.min_views, &per_view[v]);
  });
  std::vector<SurfacePoint> points;
  for (const std::vector<SurfacePoint>& view_points : per_view) {
    points.insert(points.end(), view_points.begin(), view_points.end());
  }
  return GaussiansFromPoints(points, options.max_gaussians, options.sh_degree);
}

}  // namespace p2n
