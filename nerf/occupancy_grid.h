#pragma once
// An occupancy grid over [0, 1]^3 (docs/design.md §6): which cells may hold density, refreshed from the field during
// training, so that ray marching takes no samples in empty space. Each cell keeps a decaying maximum of the
// densities seen in it (as instant-ngp does) and a bit: occupied when that value exceeds the threshold.

#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "nerf/rays.h"

namespace p2n {

struct MarchSample {
  double t;      // distance along the ray of the sample (the middle of its segment)
  double delta;  // length of its segment
};

class OccupancyGrid {
 public:
  explicit OccupancyGrid(int resolution = 128);
  // A grid saved with densities() and bits(); std::invalid_argument when the sizes do not match.
  OccupancyGrid(int resolution, std::vector<float> densities, std::vector<uint8_t> bits);
  // A grid saved with its bits alone: its occupied cells unknown (as never evaluated), the others empty.
  OccupancyGrid(int resolution, std::vector<uint8_t> bits);

  int resolution() const { return resolution_; }
  // Densities at points (3 x n, in [0, 1]^3) -> n values.
  using DensityFunction = std::function<Eigen::VectorXf(const Eigen::Matrix3Xf& points)>;
  // Decays every cell's value by `decay`; evaluates `density` at one random point in each of `cells` cells (0:
  // all), visited round-robin in a fixed scattered order, and keeps max(decayed, new); then sets the bits where
  // the value exceeds `threshold`, or the mean value when that is lower (a young field's densities are all
  // small: the cells above the mean are its best guess). A cell never evaluated counts as occupied.
  void Update(const DensityFunction& density, float threshold, float decay, uint64_t seed, size_t cells = 0);
  // One grid from several of one resolution: each cell's value and bit from grids[owner(its centre)] (a field by
  // blocks' grid, from its blocks'); std::invalid_argument when there are none or their resolutions differ.
  static OccupancyGrid Merge(const std::vector<const OccupancyGrid*>& grids,
                             const std::function<int(const Eigen::Vector3d& centre)>& owner);
  // Marks every cell occupied (the start of training: nothing is known yet).
  void MarkAllOccupied();
  // The mean value of the cells evaluated so far (0 when none).
  double MeanDensity() const;

  // Inline: ray marching asks this at every step (a ray of fox takes some 110 steps for a dozen samples).
  bool Occupied(const Eigen::Vector3d& point) const {
    int cell[3];
    for (int axis = 0; axis < 3; ++axis) {
      if (!(point[axis] >= 0 && point[axis] <= 1)) return false;
      cell[axis] = std::min(resolution_ - 1, static_cast<int>(point[axis] * resolution_));
    }
    const size_t index = CellIndex(cell[0], cell[1], cell[2]);
    return bits_[index / 8] & (1u << (index % 8));
  }
  double OccupiedFraction() const;

  // Samples every `step` along `ray` within [near, far] (in the grid's [0, 1]^3 frame), leaping over
  // unoccupied cells (the largest empty block of them around) to their exit; at most `max_samples`. With `stop`,
  // writes where the march stopped there: a march resumed from it continues the same samples.
  std::vector<MarchSample> March(const Ray& ray, double near, double far, double step, size_t max_samples,
                                 double* stop = nullptr) const;

  const std::vector<float>& densities() const { return densities_; }
  // Where the next partial update starts (kept in training checkpoints, so that a resumed run is the same).
  size_t cursor() const { return cursor_; }
  void set_cursor(size_t cursor) { cursor_ = cursor % densities_.size(); }
  const std::vector<uint8_t>& bits() const { return bits_; }

 private:
  struct Unbuilt {};
  // Sized, every cell unknown (occupied), the blocks not built yet: what the constructors start from.
  OccupancyGrid(int resolution, Unbuilt);
  size_t CellIndex(int x, int y, int z) const { return (static_cast<size_t>(z) * resolution_ + y) * resolution_ + x; }
  // The blocks from the bits (after every change of them).
  void BuildBlocks();
  // The side, in cells, of the largest empty block that holds the empty cell `cell` (1: the cell alone).
  int EmptyBlockSide(const int* cell) const;

  int resolution_;
  size_t cursor_ = 0;             // where the next partial update starts in the scattered order
  std::vector<float> densities_;  // negative: never evaluated
  std::vector<uint8_t> bits_;     // one bit per cell
  // Coarser views of the bits, for leaping over empty space in few steps: blocks_[k - 1] has a flag per block of
  // 2^k x 2^k x 2^k cells (clipped at the far faces), set when a cell in it is occupied.
  std::vector<std::vector<uint8_t>> blocks_;
};

}  // namespace p2n
