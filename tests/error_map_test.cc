// The error map: uniform draws until errors differ, then draws drawn towards the errors, with weights that keep
// a weighted mean unbiased; every draw inside its image; its state saved and restored.

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "nerf/error_map.h"

namespace p2n::testing {
namespace {

// The mean of f(view, x, y) over all pixels of the views, estimated from `draws` weighted draws.
template <class F>
double WeightedMean(const ErrorMap& map, int draws, uint64_t seed, F f) {
  std::mt19937_64 random(seed);
  double sum = 0;
  for (int i = 0; i < draws; ++i) {
    const ErrorMap::Draw draw = map.Sample(&random);
    sum += draw.weight * f(draw.view, draw.x, draw.y);
  }
  return sum / draws;
}

}  // namespace

TEST_CASE("an error map draws uniformly over all pixels until the errors differ", "[error_map]") {
  // Sizes that do not divide into the cells: the last row and column of cells are clipped.
  const ErrorMap map({{100, 37}, {50, 37}});
  std::mt19937_64 random(1);
  int first = 0;
  const int draws = 30000;
  for (int i = 0; i < draws; ++i) {
    const ErrorMap::Draw draw = map.Sample(&random);
    const int width = draw.view == 0 ? 100 : 50;
    REQUIRE(draw.x >= 0);
    REQUIRE(draw.x < width);
    REQUIRE(draw.y >= 0);
    REQUIRE(draw.y < 37);
    CHECK(draw.weight == Approx(1).epsilon(1e-5));
    first += draw.view == 0;
  }
  // Two thirds of the pixels are the first image's (binomial standard deviation 0.0027).
  CHECK(double(first) / draws == Approx(2.0 / 3).margin(0.012));
}

TEST_CASE("an error map draws more where the error is and weights its draws to stay unbiased", "[error_map]") {
  ErrorMap map({{64, 64}, {64, 64}});
  // The second image's cells are 100 times as wrong as the first's.
  for (uint32_t cell = 0; cell < map.cells(); ++cell) {
    for (int k = 0; k < 100; ++k) map.Record(cell, cell < map.cells() / 2 ? 0.01f : 1.0f);
  }
  map.Rebuild();
  // Half the draws are uniform, half go (almost all) to the second image: about 3/4 there.
  std::mt19937_64 random(2);
  int second = 0;
  for (int i = 0; i < 20000; ++i) second += map.Sample(&random).view == 1;
  CHECK(second / 20000.0 == Approx(0.5 * 0.5 + 0.5 * 100 / 101.0).margin(0.015));
  // Weighted draws estimate a mean over all pixels without bias: the mean x (31.5), the share of the first image.
  CHECK(WeightedMean(map, 40000, 3, [](size_t, int x, int) { return double(x); }) == Approx(31.5).margin(0.5));
  CHECK(WeightedMean(map, 40000, 4, [](size_t view, int, int) { return view == 0 ? 1.0 : 0.0; }) ==
        Approx(0.5).margin(0.02));
  // A non-finite or negative loss is not recorded.
  const float before = map.error(0);
  map.Record(0, std::numeric_limits<float>::quiet_NaN());
  map.Record(0, -1);
  map.Record(0, std::numeric_limits<float>::infinity());
  CHECK(map.error(0) == before);
}

TEST_CASE("an error map's state saves and loads: the same draws after, damaged state refused", "[error_map]") {
  ErrorMap map({{80, 60}});
  for (uint32_t cell = 0; cell < map.cells(); ++cell) map.Record(cell, 0.001f * cell);
  map.Rebuild();
  BinaryWriter writer;
  map.Save(&writer);
  ErrorMap loaded({{80, 60}});
  BinaryReader reader(writer.buffer(), "error map");
  loaded.Load(&reader);
  std::mt19937_64 a(5), b(5);
  for (int i = 0; i < 100; ++i) {
    const ErrorMap::Draw x = map.Sample(&a), y = loaded.Sample(&b);
    REQUIRE(x.cell == y.cell);
    REQUIRE(x.weight == y.weight);
  }
  ErrorMap other({{80, 61}, {10, 10}});
  BinaryReader wrong(writer.buffer(), "error map");
  CHECK_THROWS(other.Load(&wrong));
  CHECK_THROWS_AS(ErrorMap({{0, 10}}), std::invalid_argument);
}

}  // namespace p2n::testing
