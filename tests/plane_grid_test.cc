// The factorised encoding (three feature planes a level, multiplied): what it represents exactly, and its
// gradients against central finite differences, in double precision.

#include <catch2/catch.hpp>

#include <random>

#include "encoding_checks.h"
#include "nerf/make_field.h"
#include "nerf/ngp_field.h"
#include "nerf/plane_grid.h"

namespace p2n::testing {
namespace {

using Matrix = Eigen::MatrixXd;

// Two levels, the image plane finer than the depth axis (as for a forward-facing scene).
PlaneGridConfig SmallPlanes(int features) {
  return {.levels = 2, .features_per_level = features, .finest_resolution = 6, .depth_resolution = 4};
}

}  // namespace

TEST_CASE("planes: one level with the xy plane linear in x and the others at 1 gives x, anywhere in the cube",
          "[planes]") {
  const PlaneGridConfig config{.levels = 1, .features_per_level = 1, .finest_resolution = 5, .depth_resolution = 3};
  PlaneGridEncoding<double> planes(config, 1);
  // The xy plane's 6 x 6 vertices, x fastest, then the xz plane's 6 x 4 and the yz plane's 6 x 4.
  std::fill(planes.params(), planes.params() + planes.num_params(), 1.0);
  for (int v = 0; v <= 5; ++v) {
    for (int u = 0; u <= 5; ++u) planes.params()[v * 6 + u] = u / 5.0;
  }
  Matrix points = RandomMatrix(3, 50, 2, 0, 1);
  points.col(0) << 1, 1, 1;     // the far corner: the last cell's far edge
  points.col(1) << -3, 0.5, 7;  // outside: clamped into the cube
  Matrix out;
  planes.Forward(points, &out);
  REQUIRE(out.rows() == 1);
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    CHECK(out(0, i) == Approx(std::clamp(points(0, i), 0.0, 1.0)).margin(1e-12));
  }
}

TEST_CASE("planes: a level is the product of its three planes, each bilinear in its two coordinates", "[planes]") {
  const PlaneGridConfig config{.levels = 1, .features_per_level = 1, .finest_resolution = 1, .depth_resolution = 1};
  PlaneGridEncoding<double> planes(config, 1);
  // One cell a plane: xy = 2 + x, xz = 3 z, yz = 1 + y z.
  const double values[12] = {2, 3, 2, 3, 0, 0, 3, 3, 1, 1, 1, 2};
  std::copy(values, values + 12, planes.params());
  const Matrix points = RandomMatrix(3, 20, 3, 0, 1);
  Matrix out;
  planes.Forward(points, &out);
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const double x = points(0, i), y = points(1, i), z = points(2, i);
    CHECK(out(0, i) == Approx((2 + x) * (3 * z) * (1 + y * z)).epsilon(1e-12));
  }
}

TEST_CASE("planes: gradients of the features match finite differences, 1 to 8 features a level",
          "[planes][gradients]") {
  for (const int features : {1, 3, 8}) {
    CAPTURE(features);
    PlaneGridEncoding<double> planes(SmallPlanes(features), 3);
    const Matrix input = RandomMatrix(3, 40, 4, 0, 1);
    const Matrix weights = RandomMatrix(planes.output_dims(), 40, 5, -1, 1);
    CHECK(CheckParameterGradients(planes, input, weights) > planes.num_params() / 2);
  }
}

TEST_CASE("planes: gradients with respect to the input match finite differences, none where clamped",
          "[planes][gradients]") {
  PlaneGridEncoding<double> planes(SmallPlanes(2), 3);
  std::mt19937_64 random(6);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (size_t k = 0; k < planes.num_params(); ++k) planes.params()[k] = uniform(random);
  Matrix input = RandomMatrix(3, 9, 4, 0.01, 0.99);
  input(2, 8) = 1.5;  // clamped along z
  const Matrix weights = RandomMatrix(planes.output_dims(), 9, 5, -1, 1);
  const Matrix d_input = CheckInputGradients(planes, input, weights);
  CHECK(d_input(2, 8) == 0);
  CHECK(d_input.cwiseAbs().maxCoeff() > 0.1);
}

TEST_CASE("planes: in float with 8 features (the vector path) as in double", "[planes]") {
  PlaneGridEncoding<double> exact(SmallPlanes(8), 3);
  PlaneGridEncoding<float> planes(SmallPlanes(8), 3);
  const Matrix input = RandomMatrix(3, 300, 4, -0.1, 1.1);
  const Matrix weights = RandomMatrix(exact.output_dims(), 300, 5, -1, 1);
  Matrix out;
  Eigen::MatrixXf out_float;
  exact.Forward(input, &out);
  planes.Forward(input.cast<float>(), &out_float);
  CHECK((out_float.cast<double>() - out).cwiseAbs().maxCoeff() < 1e-6);
  exact.Backward(input, weights);
  planes.Backward(input.cast<float>(), weights.cast<float>());
  double worst = 0;
  for (size_t k = 0; k < exact.num_params(); ++k)
    worst = std::max(worst, std::abs(planes.grads()[k] - exact.grads()[k]));
  CHECK(worst < 1e-4);
}

TEST_CASE("planes: the config round-trips through the field's JSON, and bad ones are refused by name", "[planes]") {
  NgpFieldConfig config;
  config.planes =
      PlaneGridConfig{.levels = 3, .features_per_level = 4, .finest_resolution = 64, .depth_resolution = 16};
  CHECK(NgpFieldConfig::FromJson(config.ToJson()) == config);
  const auto field = MakeField<float>(config.ToJson(), 1);
  CHECK(field->Config() == config.ToJson());
  CHECK(field->TrainableEncoding()->output_dims() == 12);
  CHECK(field->TrainableEncoding()->entry_size() == 4);
  PlaneGridConfig bad = *config.planes;
  bad.depth_resolution = 2;  // less than a cell at the coarsest of 3 levels
  CHECK_THROWS_WITH(PlaneGridEncoding<float>(bad, 1), Catch::StartsWith("planes.depth_resolution must be"));
  nlohmann::json json = config.ToJson();
  json["encoding"]["rank"] = 3;
  CHECK_THROWS_WITH(NgpFieldConfig::FromJson(json), Catch::Contains("unknown key 'rank'"));
}

}  // namespace p2n::testing
