// The cut a stage working by blocks makes, for the field and the splats alike (base/slabs.h).
#include "base/slabs.h"

#include <catch2/catch.hpp>

#include <random>
#include <stdexcept>

namespace p2n {
namespace {

TEST_CASE("slabs hold equal shares of the points along the axis where they spread most", "[blocks]") {
  Eigen::Matrix3Xd points(3, 1000);
  std::mt19937 random(2);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int i = 0; i < points.cols(); ++i) points.col(i) << 0.4 + 0.1 * unit(random), unit(random), 0.5;
  const Slabs slabs = CutIntoSlabs(points, 4);
  CHECK(slabs.axis == 1);
  REQUIRE(slabs.cuts.size() == 3);
  std::vector<int> counts(4);
  for (int i = 0; i < points.cols(); ++i) ++counts[slabs.SlabOf(points(1, i))];
  for (const int count : counts) CHECK(count == Approx(250).margin(2));
  CHECK(CutIntoSlabs(points, 1).count() == 1);
  CHECK_THROWS_AS(CutIntoSlabs(points, 0), std::invalid_argument);
}

TEST_CASE("the views of a slab: those at least a share of whose points lie in it", "[blocks]") {
  const Slabs slabs{2, {0.5}};
  std::vector<Eigen::Matrix3Xd> seen(3, Eigen::Matrix3Xd(3, 10));
  for (int v = 0; v < 3; ++v) {
    for (int p = 0; p < 10; ++p) seen[v].col(p) << 0.5, 0.5, p < 2 * (v + 1) ? 0.7 : 0.2;  // 2, 4, 6 of 10 in slab 1
  }
  CHECK(ViewsOfSlab(seen, slabs, 1, 0.3) == std::vector<size_t>{1, 2});
  CHECK(ViewsOfSlab(seen, slabs, 0, 0.5) == std::vector<size_t>{0, 1});
  seen[0].resize(3, 0);  // a view that sees nothing is nobody's
  CHECK(ViewsOfSlab(seen, slabs, 0, 0.0) == std::vector<size_t>{1, 2});
}

}  // namespace
}  // namespace p2n
