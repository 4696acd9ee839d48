#include "splat/blocks.h"

#include <stdexcept>

#include "splat/scene_size.h"

namespace p2n {

Eigen::Matrix3Xd Means(const Gaussians<float>& splats) {
  return Eigen::Map<const Eigen::Matrix3Xf>(splats.positions.data(), 3, static_cast<Eigen::Index>(splats.size()))
      .cast<double>();
}

std::vector<bool> InSlab(const Gaussians<float>& splats, const Slabs& slabs, int slab) {
  std::vector<bool> in(splats.size());
  for (size_t i = 0; i < splats.size(); ++i) in[i] = slabs.SlabOf(splats.positions[3 * i + slabs.axis]) == slab;
  return in;
}

Gaussians<float> SplatsOfSlab(const Gaussians<float>& splats, const Slabs& slabs, int slab, bool inside) {
  Gaussians<float> selected = splats;
  std::vector<bool> keep = InSlab(splats, slabs, slab);
  if (!inside) keep.flip();
  selected.Filter(keep);
  return selected;
}

std::vector<size_t> ViewsOfSlab(const std::vector<TrainView>& views, const Gaussians<float>& splats, const Slabs& slabs,
                                int slab, double near) {
  const Eigen::Matrix3Xd means = Means(splats);
  std::vector<size_t> seeing;
  for (size_t v = 0; v < views.size(); ++v) {
    std::vector<Eigen::Index> in_picture;
    for (size_t i = 0; i < splats.size(); ++i) {
      if (InPicture(views[v].camera, &splats.positions[3 * i], near))
        in_picture.push_back(static_cast<Eigen::Index>(i));
    }
    if (SeesSlab(means(Eigen::all, in_picture), slabs, slab)) seeing.push_back(v);
  }
  return seeing;
}

Gaussians<float> MergeSlabs(const std::vector<Gaussians<float>>& optimised) {
  if (optimised.empty()) throw std::invalid_argument("MergeSlabs: no slabs");
  Gaussians<float> merged;
  merged.sh_degree = optimised.front().sh_degree;
  for (const Gaussians<float>& slab : optimised) merged.Append(slab);
  return merged;
}

}  // namespace p2n
