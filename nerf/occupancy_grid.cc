#include "nerf/occupancy_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "nerf/denormals.h"

namespace p2n {
namespace {

// The sweeps over every cell (16.7 M at 256^3, every 16th training step) run in parallel, in fixed blocks of cells: a
// multiple of 8, so that no two blocks share a byte of the bits, and fixed, so that sums over them do not depend on
// the threads.
constexpr size_t kSweepBlock = size_t{1} << 16;

// Calls body(begin, end) on each block of [0, n), in parallel.
template <typename Body>
void ForEachBlock(size_t n, const Body& body) {
  tbb::parallel_for(size_t{0}, (n + kSweepBlock - 1) / kSweepBlock,
                    [&](size_t b) { body(b * kSweepBlock, std::min(n, (b + 1) * kSweepBlock)); });
}

// The cells of a grid of that resolution, checked before anything is allocated.
size_t CellCount(int resolution) {
  if (resolution < 1 || resolution > 1024) throw std::invalid_argument("occupancy grid resolution must be 1..1024");
  return static_cast<size_t>(resolution) * resolution * resolution;
}

}  // namespace

OccupancyGrid::OccupancyGrid(int resolution, Unbuilt)
    : resolution_(resolution), densities_(CellCount(resolution), -1.0f), bits_((densities_.size() + 7) / 8, 0xff) {}

OccupancyGrid::OccupancyGrid(int resolution) : OccupancyGrid(resolution, Unbuilt{}) { BuildBlocks(); }

OccupancyGrid::OccupancyGrid(int resolution, std::vector<float> densities, std::vector<uint8_t> bits)
    : OccupancyGrid(resolution, Unbuilt{}) {
  if (densities.size() != densities_.size() || bits.size() != bits_.size()) {
    throw std::invalid_argument("occupancy grid: the saved values do not match the resolution");
  }
  densities_ = std::move(densities);
  bits_ = std::move(bits);
  BuildBlocks();
}

OccupancyGrid::OccupancyGrid(int resolution, std::vector<uint8_t> bits) : OccupancyGrid(resolution, Unbuilt{}) {
  if (bits.size() != bits_.size())
    throw std::invalid_argument("occupancy grid: the saved bits do not match the resolution");
  bits_ = std::move(bits);
  for (size_t cell = 0; cell < densities_.size(); ++cell) {
    if (!((bits_[cell / 8] >> (cell % 8)) & 1)) densities_[cell] = 0;
  }
  BuildBlocks();
}

OccupancyGrid OccupancyGrid::Merge(const std::vector<const OccupancyGrid*>& grids,
                                   const std::function<int(const Eigen::Vector3d& centre)>& owner) {
  if (grids.empty()) throw std::invalid_argument("OccupancyGrid::Merge: no grids");
  const int resolution = grids.front()->resolution_;
  for (const OccupancyGrid* grid : grids) {
    if (grid->resolution_ != resolution) throw std::invalid_argument("OccupancyGrid::Merge: the resolutions differ");
  }
  OccupancyGrid merged(resolution, Unbuilt{});
  std::fill(merged.bits_.begin(), merged.bits_.end(), 0);
  for (int z = 0; z < resolution; ++z) {
    for (int y = 0; y < resolution; ++y) {
      for (int x = 0; x < resolution; ++x) {
        const Eigen::Vector3d centre = (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) / resolution;
        const OccupancyGrid& from = *grids.at(owner(centre));
        const size_t cell = merged.CellIndex(x, y, z);
        merged.densities_[cell] = from.densities_[cell];
        if ((from.bits_[cell / 8] >> (cell % 8)) & 1) merged.bits_[cell / 8] |= uint8_t(1u << (cell % 8));
      }
    }
  }
  merged.BuildBlocks();
  return merged;
}

void OccupancyGrid::MarkAllOccupied() {
  std::fill(bits_.begin(), bits_.end(), 0xff);
  BuildBlocks();
}

void OccupancyGrid::BuildBlocks() {
  blocks_.clear();
  // Level k's flags from level k - 1's (level 0: the bits), up to blocks of 2^kMaxBlockLevel cells a side.
  constexpr int kMaxBlockLevel = 5;
  int previous = resolution_;  // the finer level's blocks per axis
  for (int k = 1; k <= kMaxBlockLevel && previous > 1; ++k) {
    const int size = (previous + 1) / 2;
    std::vector<uint8_t> flags(static_cast<size_t>(size) * size * size, 0);
    tbb::parallel_for(0, size, [&](int block_z) {  // each task writes its own slice of blocks
      for (int z = 2 * block_z; z < std::min(previous, 2 * block_z + 2); ++z) {
        for (int y = 0; y < previous; ++y) {
          for (int x = 0; x < previous; ++x) {
            const size_t fine = (static_cast<size_t>(z) * previous + y) * previous + x;
            const bool occupied = k == 1 ? (bits_[fine / 8] >> (fine % 8)) & 1 : blocks_.back()[fine];
            if (occupied) flags[(static_cast<size_t>(block_z) * size + y / 2) * size + x / 2] = 1;
          }
        }
      }
    });
    blocks_.push_back(std::move(flags));
    previous = size;
  }
}

int OccupancyGrid::EmptyBlockSide(const int* cell) const {
  int level = 0;
  for (; level < static_cast<int>(blocks_.size()); ++level) {
    const int size = (resolution_ + (2 << level) - 1) >> (level + 1);  // blocks per axis at level + 1
    const int shift = level + 1;
    const size_t index =
        (static_cast<size_t>(cell[2] >> shift) * size + (cell[1] >> shift)) * size + (cell[0] >> shift);
    if (blocks_[level][index]) break;
  }
  return 1 << level;
}

void OccupancyGrid::Update(const DensityFunction& density, float threshold, float decay, uint64_t seed, size_t cells) {
  const size_t total = densities_.size();
  if (cells == 0 || cells > total) cells = total;
  ForEachBlock(total, [&](size_t begin, size_t end) {
    for (size_t cell = begin; cell < end; ++cell) {
      if (densities_[cell] > 0) densities_[cell] *= decay;
    }
  });
  // Cell k of this round is (cursor + k) * stride mod total: an odd stride visits every cell of a power-of-two
  // grid once per `total` cells, scattered over the volume.
  const size_t stride = (total % 2 == 0) ? 2654435761u % total | 1 : 1;
  constexpr size_t kBatch = 4096;
  tbb::parallel_for(size_t{0}, (cells + kBatch - 1) / kBatch, [&](size_t batch) {
    FlushDenormalsOnThisThread();
    std::mt19937_64 random(seed * 1000003 + batch);
    std::uniform_real_distribution<float> jitter(0.0f, 1.0f);
    const size_t begin = batch * kBatch, end = std::min(cells, begin + kBatch);
    std::vector<size_t> indices(end - begin);
    Eigen::Matrix3Xf points(3, end - begin);
    const size_t r = static_cast<size_t>(resolution_);
    for (size_t k = begin; k < end; ++k) {
      const size_t cell = ((cursor_ + k) % total) * stride % total;
      indices[k - begin] = cell;
      points.col(k - begin) = Eigen::Vector3f((cell % r + jitter(random)) / r, (cell / r % r + jitter(random)) / r,
                                              (cell / (r * r) + jitter(random)) / r);
    }
    const Eigen::VectorXf values = density(points);
    for (size_t k = 0; k < indices.size(); ++k) {
      const float value = std::isfinite(values[k]) ? std::max(values[k], 0.0f) : 0.0f;
      densities_[indices[k]] = std::max(densities_[indices[k]], value);
    }
  });
  cursor_ = (cursor_ + cells) % total;
  threshold = std::min(threshold, static_cast<float>(MeanDensity()));
  ForEachBlock(total, [&](size_t begin, size_t end) {
    for (size_t byte = begin / 8; byte < (end + 7) / 8; ++byte) {
      uint8_t bits = 0;
      for (size_t cell = byte * 8; cell < std::min(end, byte * 8 + 8); ++cell) {
        if (densities_[cell] > threshold || densities_[cell] < 0) bits |= static_cast<uint8_t>(1u << (cell % 8));
      }
      bits_[byte] = bits;
    }
  });
  BuildBlocks();
}

double OccupancyGrid::MeanDensity() const {
  const size_t blocks = (densities_.size() + kSweepBlock - 1) / kSweepBlock;
  std::vector<double> sums(blocks, 0.0);
  std::vector<size_t> counts(blocks, 0);
  ForEachBlock(densities_.size(), [&](size_t begin, size_t end) {
    double sum = 0;
    size_t known = 0;
    for (size_t cell = begin; cell < end; ++cell) {
      if (densities_[cell] >= 0) {
        sum += densities_[cell];
        ++known;
      }
    }
    sums[begin / kSweepBlock] = sum;
    counts[begin / kSweepBlock] = known;
  });
  double sum = 0;
  size_t known = 0;
  for (size_t b = 0; b < blocks; ++b) {
    sum += sums[b];
    known += counts[b];
  }
  return known == 0 ? 0.0 : sum / known;
}

double OccupancyGrid::OccupiedFraction() const {
  size_t occupied = 0;
  for (const uint8_t byte : bits_) occupied += static_cast<size_t>(__builtin_popcount(byte));
  return static_cast<double>(occupied) / densities_.size();
}

std::vector<MarchSample> OccupancyGrid::March(const Ray& ray, double near, double far, double step, size_t max_samples,
                                              double* stop) const {
  std::vector<MarchSample> samples;
  double t = near;
  if (stop != nullptr) *stop = t;
  if (!(step > 0) || !(far > near)) return samples;
  while (t < far && samples.size() < max_samples) {
    const double middle = std::min(t + 0.5 * step, 0.5 * (t + far));
    const Eigen::Vector3d point = ray.origin + middle * ray.direction;
    if (Occupied(point)) {
      const double end = std::min(t + step, far);
      samples.push_back({0.5 * (t + end), end - t});
      t = end;
      continue;
    }
    // Leap to where the ray leaves this cell (or the empty block around it, inside the grid), then on by whole
    // steps so that samples stay on one lattice.
    int cell[3];
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      cell[axis] = static_cast<int>(std::floor(point[axis] * resolution_));
      inside = inside && cell[axis] >= 0 && cell[axis] < resolution_;
    }
    const int side = inside ? EmptyBlockSide(cell) : 1;
    double exit = far;
    for (int axis = 0; axis < 3; ++axis) {
      const double d = ray.direction[axis];
      if (d == 0) continue;
      const double block = std::floor(point[axis] * resolution_ / side) * side;  // its first cell along the axis
      const double boundary = (d > 0 ? block + side : block) / resolution_;
      exit = std::min(exit, middle + (boundary - point[axis]) / d);
    }
    t += std::max(step, std::ceil((exit - t) / step) * step);
  }
  if (stop != nullptr) *stop = t;
  return samples;
}

}  // namespace p2n
