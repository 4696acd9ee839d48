#include "nerf/occupancy_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace p2n {

OccupancyGrid::OccupancyGrid(int resolution)
    : resolution_(resolution),
      densities_(static_cast<size_t>(resolution) * resolution * resolution, 0.0f),
      bits_((densities_.size() + 7) / 8, 0) {
  if (resolution < 1 || resolution > 1024) throw std::invalid_argument("occupancy grid resolution must be 1..1024");
}

void OccupancyGrid::MarkAllOccupied() { std::fill(bits_.begin(), bits_.end(), 0xff); }

void OccupancyGrid::Update(const DensityFunction& density, float threshold, float decay, uint64_t seed) {
  const int r = resolution_;
  // One slab of z per task: a random point in each cell, evaluated in one batch.
  tbb::parallel_for(0, r, [&](int z) {
    std::mt19937_64 random(seed * 1000003 + z);
    std::uniform_real_distribution<float> jitter(0.0f, 1.0f);
    Eigen::Matrix3Xf points(3, r * r);
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        points.col(y * r + x) = Eigen::Vector3f((x + jitter(random)) / r, (y + jitter(random)) / r, (z + jitter(random)) / r);
      }
    }
    const Eigen::VectorXf values = density(points);
    for (int i = 0; i < r * r; ++i) {
      const size_t cell = static_cast<size_t>(z) * r * r + i;
      const float value = std::isfinite(values[i]) ? values[i] : 0.0f;
      densities_[cell] = std::max(decay * densities_[cell], value);
    }
  });
  std::fill(bits_.begin(), bits_.end(), 0);
  for (size_t cell = 0; cell < densities_.size(); ++cell) {
    if (densities_[cell] > threshold) bits_[cell / 8] |= static_cast<uint8_t>(1u << (cell % 8));
  }
}

bool OccupancyGrid::Occupied(const Eigen::Vector3d& point) const {
  int cell[3];
  for (int axis = 0; axis < 3; ++axis) {
    if (!(point[axis] >= 0 && point[axis] <= 1)) return false;
    cell[axis] = std::min(resolution_ - 1, static_cast<int>(point[axis] * resolution_));
  }
  const size_t index = CellIndex(cell[0], cell[1], cell[2]);
  return bits_[index / 8] & (1u << (index % 8));
}

double OccupancyGrid::OccupiedFraction() const {
  size_t occupied = 0;
  for (const uint8_t byte : bits_) occupied += static_cast<size_t>(__builtin_popcount(byte));
  return static_cast<double>(occupied) / densities_.size();
}

std::vector<MarchSample> OccupancyGrid::March(const Ray& ray, double near, double far, double step,
                                              size_t max_samples) const {
  std::vector<MarchSample> samples;
  if (!(step > 0) || !(far > near)) return samples;
  double t = near;
  while (t < far && samples.size() < max_samples) {
    const double middle = std::min(t + 0.5 * step, 0.5 * (t + far));
    const Eigen::Vector3d point = ray.origin + middle * ray.direction;
    if (Occupied(point)) {
      const double end = std::min(t + step, far);
      samples.push_back({0.5 * (t + end), end - t});
      t = end;
      continue;
    }
    // Leap to where the ray leaves this cell, then on by whole steps so that samples stay on one lattice.
    double exit = far;
    for (int axis = 0; axis < 3; ++axis) {
      const double d = ray.direction[axis];
      if (d == 0) continue;
      const double cell = std::floor(point[axis] * resolution_);
      const double boundary = (d > 0 ? cell + 1 : cell) / resolution_;
      exit = std::min(exit, middle + (boundary - point[axis]) / d);
    }
    t += std::max(step, std::ceil((exit - t) / step) * step);
  }
  return samples;
}

}  // namespace p2n
