// The occupancy grid: empty space takes no samples; occupied space is sampled on the step lattice.

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "nerf/occupancy_grid.h"

namespace p2n::testing {
namespace {

// Density 1 inside a ball of radius 0.25 around the cube's centre, 0 outside.
Eigen::VectorXf Ball(const Eigen::Matrix3Xf& points) {
  return ((points.colwise() - Eigen::Vector3f::Constant(0.5f)).colwise().norm().array() < 0.25f)
      .cast<float>()
      .transpose();
}

}  // namespace

TEST_CASE("occupancy grid: empty space takes no samples, a full grid samples the whole segment", "[occupancy]") {
  OccupancyGrid grid(32);
  const Ray ray{{-0.5, 0.3, 0.6}, Eigen::Vector3d(1, 0.1, -0.05).normalized()};
  CHECK(grid.OccupiedFraction() == 1.0);  // nothing is known yet
  grid.Update([](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Zero(p.cols()); }, 0.1f, 0.9f, 1);
  CHECK(grid.March(ray, 0.5, 1.6, 0.01, 10000).empty());
  grid.MarkAllOccupied();
  const auto samples = grid.March(ray, 0.5, 1.5, 0.01, 10000);
  CHECK(samples.size() == 100);
  double covered = 0;
  for (const MarchSample& s : samples) covered += s.delta;
  CHECK(covered == Approx(1.0));
  CHECK(grid.March(ray, 0.5, 1.5, 0.01, 7).size() == 7);  // the cap
  CHECK(grid.OccupiedFraction() == 1.0);
}

TEST_CASE("occupancy grid: updated from a density, it samples only where the density is", "[occupancy]") {
  OccupancyGrid grid(64);
  grid.Update(Ball, 0.5f, 0.95f, 7);
  const double ball = 4.0 / 3.0 * M_PI * std::pow(0.25, 3);
  CHECK(grid.OccupiedFraction() == Approx(ball).epsilon(0.1));
  const Ray ray{{0.0, 0.5, 0.5}, {1, 0, 0}};
  const auto samples = grid.March(ray, 0.0, 1.0, 1e-3, 100000);
  // The ball's chord (0.5), give or take a cell at each end (a boundary cell is occupied when its random point
  // falls inside the ball).
  CHECK(samples.size() >= 468);
  CHECK(samples.size() <= 532);
  for (const MarchSample& s : samples) CHECK(std::abs(s.t - 0.5) < 0.25 + 1.5 / 64);
  // A ray that passes beside the ball takes none.
  CHECK(grid.March({{0.0, 0.05, 0.05}, {1, 0, 0}}, 0.0, 1.0, 1e-3, 100000).empty());
}

TEST_CASE("occupancy grid: densities decay, so space that empties is freed", "[occupancy]") {
  OccupancyGrid grid(8);
  grid.Update([](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Constant(p.cols(), 4.0f); }, 1.0f, 0.5f, 1);
  CHECK(grid.OccupiedFraction() == 1.0);
  const auto nothing = [](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Zero(p.cols()); };
  grid.Update(nothing, 1.0f, 0.5f, 2);  // 2: still above the threshold
  CHECK(grid.OccupiedFraction() == 1.0);
  grid.Update(nothing, 1.0f, 0.5f, 3);  // 1: not above it
  CHECK(grid.OccupiedFraction() == 0.0);
  CHECK(grid.densities()[0] == 1.0f);
  // Non-finite densities count as empty.
  grid.Update([](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Constant(p.cols(), NAN); }, 0.1f, 0.0f, 4);
  CHECK(grid.OccupiedFraction() == 0.0);
}

TEST_CASE("occupancy grid: partial updates visit every cell once per round and keep unknown cells occupied",
          "[occupancy]") {
  OccupancyGrid grid(16);
  const size_t cells = 16 * 16 * 16;
  const auto nothing = [](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Zero(p.cols()); };
  for (int round = 0; round < 4; ++round) {
    grid.Update(nothing, 0.5f, 0.9f, round, cells / 4);
    CHECK(grid.OccupiedFraction() == Approx(1.0 - 0.25 * (round + 1)));
  }
  CHECK(grid.MeanDensity() == 0.0);
  // A saved grid comes back the same.
  const OccupancyGrid copy(16, grid.densities(), grid.bits());
  CHECK(copy.OccupiedFraction() == 0.0);
  CHECK_THROWS_AS(OccupancyGrid(8, grid.densities(), grid.bits()), std::invalid_argument);
  // A grid saved with its bits alone marches as the original does; its occupied cells are unknown, the rest empty.
  grid.MarkAllOccupied();
  grid.Update(Ball, 0.5f, 0.9f, 9);
  const OccupancyGrid bits_alone(16, grid.bits());
  const Ray ray{{0.0, 0.45, 0.55}, Eigen::Vector3d(1, 0.05, 0).normalized()};
  CHECK(bits_alone.March(ray, 0, 1.2, 0.003, 1000).size() == grid.March(ray, 0, 1.2, 0.003, 1000).size());
  CHECK(bits_alone.OccupiedFraction() == grid.OccupiedFraction());
  CHECK(bits_alone.densities()[0] == 0.0f);                  // a corner: empty
  CHECK(bits_alone.densities()[(8 * 16 + 8) * 16 + 8] < 0);  // the centre: occupied, its density unknown
  CHECK_THROWS_AS(OccupancyGrid(8, grid.bits()), std::invalid_argument);
}

TEST_CASE("occupancy grid: leaping over empty blocks keeps every sample the lattice gives in occupied cells",
          "[occupancy]") {
  // Small balls scattered through a grid whose side is not a power of two (blocks clipped at the far faces).
  OccupancyGrid grid(100);
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::Matrix3Xf centres(3, 12);
  for (int c = 0; c < 12; ++c) centres.col(c) = Eigen::Vector3f(unit(random), unit(random), unit(random));
  grid.Update(
      [&](const Eigen::Matrix3Xf& p) {
        Eigen::VectorXf density = Eigen::VectorXf::Zero(p.cols());
        for (Eigen::Index i = 0; i < p.cols(); ++i)
          density[i] = (centres.colwise() - p.col(i)).colwise().norm().minCoeff() < 0.06f;
        return density;
      },
      0.5f, 0.9f, 1);
  REQUIRE(grid.OccupiedFraction() > 0.005);
  REQUIRE(grid.OccupiedFraction() < 0.2);
  size_t marched = 0;
  for (int r = 0; r < 300; ++r) {
    const Eigen::Vector3d origin(unit(random), unit(random), unit(random));
    const Ray ray{origin, Eigen::Vector3d(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5).normalized()};
    const double near = 0.01, far = 2, step = 1.0 / 700;
    // The lattice's samples in occupied cells, and how many runs of them there are.
    std::vector<double> lattice;
    size_t runs = 0;
    bool previous = false;
    for (double t = near; t < far; t += step) {
      const double middle = std::min(t + 0.5 * step, 0.5 * (t + far));
      const bool occupied = grid.Occupied(ray.origin + middle * ray.direction);
      if (occupied) lattice.push_back(middle);
      runs += occupied && !previous;
      previous = occupied;
    }
    const std::vector<MarchSample> samples = grid.March(ray, near, far, step, 100000);
    for (const MarchSample& s : samples) {
      REQUIRE(grid.Occupied(ray.origin + s.t * ray.direction));
      const double k = (s.t - 0.5 * s.delta - near) / step;
      REQUIRE(std::abs(k - std::round(k)) < 1e-6);
    }
    // A leap lands on the first lattice point past an empty cell's exit, which may skip one at a run's start.
    CHECK(samples.size() <= lattice.size());
    CHECK(samples.size() + runs >= lattice.size());
    marched += samples.size();
  }
  CHECK(marched > 300);
}

}  // namespace p2n::testing
