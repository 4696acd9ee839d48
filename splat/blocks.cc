#include "splat/blocks.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "splat/scene_size.h"

namespace p2n {

int SplatBlocks::BlockOf(const float* position) const {
  return static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), position[axis]) - cuts.begin());
}

namespace {

// The value at `share` (0..1) of the way through `values`, which it partly sorts.
float Quantile(std::vector<float>& values, double share) {
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(share * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace

SplatBlocks CutIntoBlocks(const Gaussians<float>& splats, int count) {
  if (count < 1) throw std::invalid_argument("CutIntoBlocks: " + std::to_string(count) + " blocks");
  SplatBlocks blocks;
  if (count == 1 || splats.size() == 0) return blocks;
  std::vector<std::vector<float>> coordinates(3, std::vector<float>(splats.size()));
  for (size_t i = 0; i < splats.size(); ++i) {
    for (int a = 0; a < 3; ++a) coordinates[a][i] = splats.positions[3 * i + a];
  }
  double widest = -1;
  for (int a = 0; a < 3; ++a) {
    const double spread = Quantile(coordinates[a], 0.95) - Quantile(coordinates[a], 0.05);
    if (spread > widest) widest = spread, blocks.axis = a;
  }
  for (int b = 1; b < count; ++b) blocks.cuts.push_back(Quantile(coordinates[blocks.axis], double(b) / count));
  std::sort(blocks.cuts.begin(), blocks.cuts.end());
  return blocks;
}

std::vector<bool> InBlock(const Gaussians<float>& splats, const SplatBlocks& blocks, int block) {
  std::vector<bool> in(splats.size());
  for (size_t i = 0; i < splats.size(); ++i) in[i] = blocks.BlockOf(&splats.positions[3 * i]) == block;
  return in;
}

Gaussians<float> SplatsOfBlock(const Gaussians<float>& splats, const SplatBlocks& blocks, int block, bool inside) {
  Gaussians<float> selected = splats;
  std::vector<bool> keep = InBlock(splats, blocks, block);
  if (!inside) keep.flip();
  selected.Filter(keep);
  return selected;
}

std::vector<size_t> ViewsOfBlock(const std::vector<TrainView>& views, const Gaussians<float>& splats,
                                 const SplatBlocks& blocks, int block, double min_share, double near) {
  std::vector<size_t> seeing;
  for (size_t v = 0; v < views.size(); ++v) {
    const PinholeCamera& camera = views[v].camera;
    size_t in_view = 0, in_block = 0;
    for (size_t i = 0; i < splats.size(); ++i) {
      const float* p = &splats.positions[3 * i];
      if (!InPicture(camera, p, near)) continue;
      ++in_view;
      if (blocks.BlockOf(p) == block) ++in_block;
    }
    if (in_block > 0 && in_block >= min_share * in_view) seeing.push_back(v);
  }
  return seeing;
}

Gaussians<float> MergeBlocks(const std::vector<Gaussians<float>>& optimised) {
  if (optimised.empty()) throw std::invalid_argument("MergeBlocks: no blocks");
  Gaussians<float> merged;
  merged.sh_degree = optimised.front().sh_degree;
  for (const Gaussians<float>& block : optimised) merged.Append(block);
  return merged;
}

}  // namespace p2n
