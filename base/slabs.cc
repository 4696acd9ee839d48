#include "base/slabs.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "base/float_image.h"

namespace p2n {

int Slabs::SlabOf(double coordinate) const {
  return static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), coordinate) - cuts.begin());
}

Slabs CutIntoSlabs(const Eigen::Matrix3Xd& points, int count) {
  if (count < 1 || count > kMaxSlabs) {
    throw std::invalid_argument("CutIntoSlabs: " + std::to_string(count) + " slabs (1 to " + std::to_string(kMaxSlabs) +
                                ")");
  }
  Slabs slabs;
  if (count == 1 || points.cols() == 0) return slabs;
  std::vector<std::vector<double>> coordinates(3);
  double widest = -1;
  for (int a = 0; a < 3; ++a) {
    coordinates[a].assign(points.row(a).begin(), points.row(a).end());
    const double spread = Quantile(coordinates[a], 0.95) - Quantile(coordinates[a], 0.05);
    if (spread > widest) widest = spread, slabs.axis = a;
  }
  for (int b = 1; b < count; ++b) {
    const double cut = Quantile(coordinates[slabs.axis], double(b) / count);
    if (slabs.cuts.empty() || cut > slabs.cuts.back()) slabs.cuts.push_back(cut);  // equal quantiles: one cut
  }
  return slabs;
}

bool SeesSlab(const Eigen::Matrix3Xd& seen, const Slabs& slabs, int slab, double min_share) {
  Eigen::Index in_slab = 0;
  for (Eigen::Index p = 0; p < seen.cols(); ++p) in_slab += slabs.SlabOf(seen(slabs.axis, p)) == slab;
  return in_slab > 0 && in_slab >= min_share * seen.cols();
}

std::vector<size_t> ViewsOfSlab(const std::vector<Eigen::Matrix3Xd>& seen, const Slabs& slabs, int slab,
                                double min_share) {
  std::vector<size_t> views;
  for (size_t v = 0; v < seen.size(); ++v) {
    if (SeesSlab(seen[v], slabs, slab, min_share)) views.push_back(v);
  }
  return views;
}

}  // namespace p2n
