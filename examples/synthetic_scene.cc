#include "examples/synthetic_scene.h"

#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>

#include "base/image_io.h"

namespace p2n {
namespace {

using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;
constexpr double kNoHit = std::numeric_limits<double>::infinity();

// Value noise on the integer lattice with a fixed integer hash: the same on every platform.
double LatticeValue(int64_t x, int64_t y, int64_t z, uint32_t channel) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
               static_cast<uint64_t>(z) * 0x165667B19E3779F9ull ^ (uint64_t{channel} << 32);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(uint64_t{1} << 53);
}

double Smooth(double t) { return t * t * (3 - 2 * t); }

double ValueNoise(const Vector3d& p, uint32_t channel) {
  const Vector3d floor = p.array().floor();
  const Vector3d f = p - floor;
  const int64_t x = static_cast<int64_t>(floor.x()), y = static_cast<int64_t>(floor.y()),
                z = static_cast<int64_t>(floor.z());
  double result = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const double weight = (dx ? Smooth(f.x()) : 1 - Smooth(f.x())) * (dy ? Smooth(f.y()) : 1 - Smooth(f.y())) *
                          (dz ? Smooth(f.z()) : 1 - Smooth(f.z()));
    result += weight * LatticeValue(x + dx, y + dy, z + dz, channel);
  }
  return result;
}

// Fractal noise in [0, 1): octaves of value noise.
double Fractal(const Vector3d& p, uint32_t channel) {
  double sum = 0, amplitude = 0.5, frequency = 1, total = 0;
  for (int octave = 0; octave < 5; ++octave) {
    sum += amplitude * ValueNoise(p * frequency, channel + 17 * octave);
    total += amplitude;
    amplitude *= 0.5;
    frequency *= 2.03;
  }
  return sum / total;
}

struct Material {
  Vector3d base;  // mean colour
  double scale;   // texture frequency
  uint32_t seed;
};

// A solid texture: coloured fractal blotches with sharp speckles at three scales, dark and bright, so that SIFT
// finds corners at every distance the cameras see the surface from.
Vector3d Texture(const Vector3d& p, const Material& material) {
  const Vector3d q = p * material.scale;
  const Vector3d tint(Fractal(q, material.seed), Fractal(q, material.seed + 1), Fractal(q, material.seed + 2));
  Vector3d colour = (material.base + 0.8 * (tint.array() - 0.5).matrix()).cwiseMax(0.0).cwiseMin(1.0);
  const double frequencies[] = {3.1, 8.3, 19.7};
  for (int k = 0; k < 3; ++k) {
    if (ValueNoise(q * frequencies[k], material.seed + 3 + k) > 0.76) {
      colour = k == 1 ? (0.3 * colour).eval() : (0.25 * colour + Vector3d::Constant(0.75)).eval();
    }
  }
  return colour;
}

struct Sphere {
  Vector3d centre;
  double radius;
  Material material;
};

struct Box {
  Vector3d low, high;
  Material material;
};

const Material kGround{{0.55, 0.5, 0.4}, 2.0, 11};
const Sphere kSpheres[] = {
    {{0.0, 0.0, 0.7}, 0.7, {{0.7, 0.35, 0.3}, 3.0, 23}},
    {{-1.2, 0.9, 0.4}, 0.4, {{0.3, 0.5, 0.75}, 5.0, 37}},
};
const Box kBoxes[] = {
    {{0.8, -1.1, 0.0}, {1.5, -0.4, 0.9}, {{0.35, 0.65, 0.35}, 4.0, 51}},
    {{-1.4, -1.2, 0.0}, {-0.6, -0.5, 0.5}, {{0.75, 0.7, 0.3}, 4.5, 67}},
};
constexpr double kGroundHalfSize = 4.0;
const Vector3d kSkyColour(0.62, 0.72, 0.85);
const Vector3d kLightDirection = Vector3d(0.4, 0.3, 1.0).normalized();

double HitSphere(const Vector3d& origin, const Vector3d& direction, const Sphere& sphere) {
  const Vector3d oc = origin - sphere.centre;
  const double b = oc.dot(direction);
  const double c = oc.squaredNorm() - sphere.radius * sphere.radius;
  const double discriminant = b * b - c;
  if (discriminant < 0) return kNoHit;
  const double root = std::sqrt(discriminant);
  if (-b - root > 1e-9) return -b - root;
  return -b + root > 1e-9 ? -b + root : kNoHit;
}

double HitBox(const Vector3d& origin, const Vector3d& direction, const Box& box, Vector3d* normal) {
  double t_near = -kNoHit, t_far = kNoHit;
  int axis_near = 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(direction[axis]) < 1e-12) {
      if (origin[axis] < box.low[axis] || origin[axis] > box.high[axis]) return kNoHit;
      continue;
    }
    double t0 = (box.low[axis] - origin[axis]) / direction[axis];
    double t1 = (box.high[axis] - origin[axis]) / direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      axis_near = axis;
    }
    t_far = std::min(t_far, t1);
  }
  if (t_near > t_far || t_near <= 1e-9) return kNoHit;
  *normal = Vector3d::Zero();
  (*normal)[axis_near] = direction[axis_near] > 0 ? -1 : 1;
  return t_near;
}

double BoxDistance(const Vector3d& point, const Box& box) {
  const Vector3d centre = 0.5 * (box.low + box.high), half = 0.5 * (box.high - box.low);
  const Vector3d q = (point - centre).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

Vector3d Shade(const Vector3d& origin, const Vector3d& direction) {
  double best = kNoHit;
  Vector3d normal = Vector3d::UnitZ();
  const Material* material = nullptr;
  if (direction.z() < 0) {
    const double t = -origin.z() / direction.z();
    const Vector3d p = origin + t * direction;
    if (std::abs(p.x()) < kGroundHalfSize && std::abs(p.y()) < kGroundHalfSize) {
      best = t;
      material = &kGround;
    }
  }
  for (const Sphere& sphere : kSpheres) {
    const double t = HitSphere(origin, direction, sphere);
    if (t < best) {
      best = t;
      normal = (origin + t * direction - sphere.centre).normalized();
      material = &sphere.material;
    }
  }
  for (const Box& box : kBoxes) {
    Vector3d box_normal;
    const double t = HitBox(origin, direction, box, &box_normal);
    if (t < best) {
      best = t;
      normal = box_normal;
      material = &box.material;
    }
  }
  if (material == nullptr) return kSkyColour;
  const Vector3d point = origin + best * direction;
  const double diffuse = std::max(0.0, normal.dot(kLightDirection));
  return Texture(point, *material) * (0.35 + 0.65 * diffuse);
}

}  // namespace

PinholeCamera LookAtCamera(const Vector3d& position, const Vector3d& target, int width, int height, double fov_x_deg) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 0.5 * width / std::tan(0.5 * fov_x_deg * kPi / 180);
  camera.cx = 0.5 * width;
  camera.cy = 0.5 * height;
  camera.world_from_cam = LookAtPose(position, target);
  return camera;
}

namespace {

// A drone's survey: rows across the ground at kSurveyHeight, back and forth, each camera looking ahead and down
// (kSurveyTilt from straight down), so that a view sees a small part of the scene.
std::vector<PinholeCamera> SurveyCameras(const SyntheticSceneOptions& options) {
  constexpr double kSurveyHeight = 2.5, kSurveyHalfWidth = 3, kSurveyTilt = 30 * kPi / 180;
  const int rows = std::max(1, static_cast<int>(std::lround(std::sqrt(options.num_views))));
  const int per_row = (options.num_views + rows - 1) / rows;
  const auto across = [&](int k, int count) {
    return count > 1 ? -kSurveyHalfWidth + 2 * kSurveyHalfWidth * k / (count - 1) : 0.0;
  };
  std::vector<PinholeCamera> cameras;
  for (int i = 0; i < options.num_views; ++i) {
    const int row = i / per_row;
    const double heading = row % 2 == 0 ? 1 : -1;
    const Vector3d position(heading * across(i % per_row, per_row), across(row, rows), kSurveyHeight);
    const Vector3d target = position + Vector3d(heading * kSurveyHeight * std::tan(kSurveyTilt), 0, -kSurveyHeight);
    cameras.push_back(LookAtCamera(position, target, options.width, options.height, options.fov_x_deg));
  }
  return cameras;
}

}  // namespace

std::vector<PinholeCamera> SyntheticCameras(const SyntheticSceneOptions& options) {
  if (options.path == "survey") return SurveyCameras(options);
  if (options.path != "orbit" && options.path != "handheld") {
    throw std::invalid_argument("unknown camera path '" + options.path + "': use orbit, handheld or survey");
  }
  std::vector<PinholeCamera> cameras;
  const Vector3d target(0, 0, 0.4);
  const double degree = kPi / 180;
  std::mt19937_64 random(options.seed);
  std::normal_distribution<double> noise(0, 1);
  for (int i = 0; i < options.num_views; ++i) {
    const double t = options.num_views > 1 ? static_cast<double>(i) / (options.num_views - 1) : 0.0;
    double azimuth = 2 * kPi * i / options.num_views;
    double elevation =
        (options.min_elevation_deg + t * (options.max_elevation_deg - options.min_elevation_deg)) * degree;
    double radius = options.radius;
    Vector3d aim = target;
    double roll = 0;
    if (options.path == "handheld") {
      // Someone walking 140 degrees around the front of the scene, the camera held unsteadily.
      azimuth = (-70 + 140 * t) * degree + 2 * degree * noise(random);
      elevation = 0.5 * (options.min_elevation_deg + options.max_elevation_deg) * degree + 3 * degree * noise(random);
      radius *= 1 + 0.05 * noise(random);
      aim += 0.1 * Vector3d(noise(random), noise(random), noise(random));
      roll = 3 * degree * noise(random);
    }
    const Vector3d position = target + radius * Vector3d(std::cos(elevation) * std::cos(azimuth),
                                                         std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    PinholeCamera camera = LookAtCamera(position, aim, options.width, options.height, options.fov_x_deg);
    camera.world_from_cam.topLeftCorner<3, 3>() =
        camera.world_from_cam.topLeftCorner<3, 3>() * Eigen::AngleAxisd(roll, Vector3d::UnitZ()).toRotationMatrix();
    cameras.push_back(camera);
  }
  return cameras;
}

OIIO::ImageBuf RenderSyntheticView(const PinholeCamera& camera, int supersampling) {
  OIIO::ImageBuf image(OIIO::ImageSpec(camera.width, camera.height, 3, OIIO::TypeDesc::UINT8));
  uint8_t* pixels = static_cast<uint8_t*>(image.localpixels());
  const Eigen::Matrix3d rotation = camera.world_from_cam.block<3, 3>(0, 0);
  const Vector3d origin = camera.world_from_cam.block<3, 1>(0, 3);
  const int n = std::max(1, supersampling);
  tbb::parallel_for(0, camera.height, [&](int row) {
    for (int column = 0; column < camera.width; ++column) {
      Vector3d sum = Vector3d::Zero();
      for (int sy = 0; sy < n; ++sy) {
        for (int sx = 0; sx < n; ++sx) {
          const double u = column + (sx + 0.5) / n, v = row + (sy + 0.5) / n;
          const Vector3d in_cam((u - camera.cx) / camera.fx, -(v - camera.cy) / camera.fy, -1.0);
          sum += Shade(origin, (rotation * in_cam).normalized());
        }
      }
      const Vector3d colour = sum / (n * n);
      for (int c = 0; c < 3; ++c) {
        // Encode as sRGB-like gamma so the photos look like photos.
        const double encoded = std::pow(std::clamp(colour[c], 0.0, 1.0), 1 / 2.2);
        pixels[(static_cast<size_t>(row) * camera.width + column) * 3 + c] =
            static_cast<uint8_t>(std::lround(encoded * 255));
      }
    }
  });
  return image;
}

void WriteSyntheticScene(const SyntheticSceneOptions& options, const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder);
  const std::vector<PinholeCamera> cameras = SyntheticCameras(options);
  nlohmann::json frames = nlohmann::json::array();
  for (size_t i = 0; i < cameras.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "view_%03zu.png", i);
    const std::string error = WriteImage(RenderSyntheticView(cameras[i], options.supersampling), folder / name);
    if (!error.empty()) throw std::runtime_error(error);
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
      matrix.push_back({cameras[i].world_from_cam(r, 0), cameras[i].world_from_cam(r, 1),
                        cameras[i].world_from_cam(r, 2), cameras[i].world_from_cam(r, 3)});
    }
    frames.push_back({{"file_path", name}, {"transform_matrix", matrix}});
  }
  const PinholeCamera& first = cameras.front();
  const nlohmann::json truth = {{"camera_angle_x", options.fov_x_deg * kPi / 180},
                                {"fl_x", first.fx},
                                {"fl_y", first.fy},
                                {"cx", first.cx},
                                {"cy", first.cy},
                                {"w", first.width},
                                {"h", first.height},
                                {"frames", frames}};
  const std::filesystem::path path = folder / "ground_truth_cameras.json";
  std::ofstream out(path);
  out.precision(17);
  out << truth.dump(2) << "\n";
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
}

double SyntheticSignedDistance(const Eigen::Vector3d& point) {
  const Vector3d beyond(std::max(0.0, std::abs(point.x()) - kGroundHalfSize),
                        std::max(0.0, std::abs(point.y()) - kGroundHalfSize), point.z());
  double distance = beyond.norm();
  for (const Sphere& sphere : kSpheres) distance = std::min(distance, (point - sphere.centre).norm() - sphere.radius);
  for (const Box& box : kBoxes) distance = std::min(distance, BoxDistance(point, box));
  return distance;
}

std::vector<Eigen::Vector3d> SyntheticSurfacePoints(double spacing) {
  std::vector<Vector3d> points;
  for (const Sphere& sphere : kSpheres) {  // a Fibonacci lattice
    const int n = static_cast<int>(4 * kPi * sphere.radius * sphere.radius / (spacing * spacing));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - (2 * i + 1.0) / n, r = std::sqrt(1 - z * z), angle = i * kPi * (3 - std::sqrt(5.0));
      const Vector3d p = sphere.centre + sphere.radius * Vector3d(r * std::cos(angle), r * std::sin(angle), z);
      if (p.z() > 0) points.push_back(p);
    }
  }
  const auto inside_a_box = [](const Vector3d& p) {
    for (const Box& box : kBoxes) {
      if (BoxDistance(p, box) < -1e-9) return true;
    }
    return false;
  };
  for (const Box& box : kBoxes) {  // a grid on each face but the bottom
    for (int axis = 0; axis < 3; ++axis) {
      for (const int side : {0, 1}) {
        if (axis == 2 && side == 0) continue;
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (double a = box.low[u] + spacing / 2; a < box.high[u]; a += spacing) {
          for (double b = box.low[v] + spacing / 2; b < box.high[v]; b += spacing) {
            Vector3d p;
            p[axis] = side ? box.high[axis] : box.low[axis];
            p[u] = a;
            p[v] = b;
            points.push_back(p);
          }
        }
      }
    }
  }
  for (double x = -kGroundHalfSize + spacing / 2; x < kGroundHalfSize; x += spacing) {
    for (double y = -kGroundHalfSize + spacing / 2; y < kGroundHalfSize; y += spacing) {
      const Vector3d p(x, y, 0);
      if (!inside_a_box(p + Vector3d(0, 0, 1e-6))) points.push_back(p);
    }
  }
  return points;
}

}  // namespace p2n
