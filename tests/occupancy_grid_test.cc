// The occupancy grid: empty space takes no samples; occupied space is sampled on the step lattice.

#include <catch2/catch.hpp>

#include <cmath>

#include "nerf/occupancy_grid.h"

namespace p2n::testing {
namespace {

// Density 1 inside a ball of radius 0.25 around the cube's centre, 0 outside.
Eigen::VectorXf Ball(const Eigen::Matrix3Xf& points) {
  return ((points.colwise() - Eigen::Vector3f::Constant(0.5f)).colwise().norm().array() < 0.25f).cast<float>().transpose();
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
}

}  // namespace p2n::testing
