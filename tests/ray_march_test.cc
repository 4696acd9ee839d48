#include "nerf/ray_march.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "nerf/renderer.h"

namespace p2n {
namespace {

// An occupancy grid of 32^3 cells with empty blocks of several sizes among occupied ones.
OccupancyGrid PatchyGrid() {
  constexpr int kResolution = 32;
  const size_t cells = size_t{kResolution} * kResolution * kResolution;
  std::vector<uint8_t> bits((cells + 7) / 8, 0);
  for (int z = 0; z < kResolution; ++z) {
    for (int y = 0; y < kResolution; ++y) {
      for (int x = 0; x < kResolution; ++x) {
        if ((x / 4 + y / 3 + z / 5) % 3 == 0 || (x * 7 + y * 3 + z) % 11 == 0) {
          const size_t cell = (size_t(z) * kResolution + y) * kResolution + x;
          bits[cell / 8] |= static_cast<uint8_t>(1u << (cell % 8));
        }
      }
    }
  }
  return OccupancyGrid(kResolution, std::vector<float>(cells, 1.0f), bits);
}

}  // namespace

TEST_CASE("a march taken in pieces gives the samples of one march, in every scene space and with jitter",
          "[renderer]") {
  NerfModel model;
  model.occupancy = PatchyGrid();
  model.forward.near = 1;
  model.forward.tan_x = 0.5;
  model.forward.tan_y = 0.25;
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double step = 0.02;
  for (const SceneSpace space : {SceneSpace::kBounded, SceneSpace::kUnbounded, SceneSpace::kForward}) {
    for (const int stratified : {0, 24}) {
      model.space = space;
      model.stratified_samples = stratified;
      size_t total = 0;
      for (int r = 0; r < 40; ++r) {
        // Every fourth ray starts beyond the forward frame's near plane (z = -1): its march starts at its origin.
        const double z = r % 4 == 3 ? -1.2 - 0.3 * std::abs(uniform(random)) : 2 + uniform(random);
        const Eigen::Vector3d origin(0.5 * uniform(random), 0.5 * uniform(random), z);
        const Eigen::Vector3d target(0.8 * uniform(random), 0.8 * uniform(random), -1 + 0.5 * uniform(random));
        const Ray ray{origin, (target - origin).normalized()};
        const double near = r % 3 == 0 ? -1.0 : 0.5 + 0.5 * uniform(random);
        const double far = r % 3 == 0 ? -1.0 : near + 2 + uniform(random);
        for (const bool jitter : {false, true}) {
          std::mt19937_64 whole_jitter(r), pieces_jitter(r), first_jitter(r);
          const std::vector<MarchSample> whole =
              SampleRay(model, ray, near, far, step, 100000, jitter ? &whole_jitter : nullptr);
          RayMarch march(model, ray, near, far, step, jitter ? &pieces_jitter : nullptr);
          std::vector<MarchSample> pieces;
          for (size_t piece = 1; march.Next(piece, &pieces) > 0; piece = piece % 7 + 1) {
          }
          INFO("space " << int(space) << ", stratified " << stratified << ", ray " << r << ", jitter " << jitter);
          REQUIRE(pieces.size() == whole.size());
          if (!whole.empty()) CHECK(whole.front().t >= (near >= 0 ? near : 0.0));  // not behind the origin or near
          for (size_t k = 0; k < whole.size(); ++k) {
            CHECK(pieces[k].t == whole[k].t);
            CHECK(pieces[k].delta == whole[k].delta);
          }
          // A march cut short takes the first samples of the whole.
          const std::vector<MarchSample> first =
              SampleRay(model, ray, near, far, step, 5, jitter ? &first_jitter : nullptr);
          REQUIRE(first.size() == std::min<size_t>(5, whole.size()));
          for (size_t k = 0; k < first.size(); ++k) CHECK(first[k].t == whole[k].t);
          total += whole.size();
        }
      }
      CHECK(total > 200);  // the rays cross occupied cells
    }
  }
}

}  // namespace p2n
