// Gradients of the MLP and the encodings against central finite differences, in double precision.

#include <catch2/catch.hpp>

#include <random>
#include <stdexcept>

#include "encoding_checks.h"
#include "nerf/encoding.h"
#include "nerf/make_field.h"
#include "nerf/mlp.h"

namespace p2n::testing {
namespace {

using Matrix = Eigen::MatrixXd;

// L = sum(weights .* f(x)): a scalar loss with a known gradient dL/df = weights.
double MlpLoss(const Mlp<double>& mlp, const Matrix& input, const Matrix& weights) {
  Matrix out;
  Mlp<double>::Cache cache;
  mlp.Forward(input, &out, &cache);
  return (out.array() * weights.array()).sum();
}

// Four levels, the coarse one dense and the fine ones hashed (64 entries a level).
HashGridConfig SmallGridConfig() {
  HashGridConfig config;
  config.levels = 4;
  config.features_per_level = 2;
  config.log2_table_size = 6;
  config.base_resolution = 2;
  config.finest_resolution = 20;
  return config;
}

}  // namespace

TEST_CASE("MLP gradients match finite differences", "[gradients]") {
  for (const OutputActivation activation : {OutputActivation::kNone, OutputActivation::kSigmoid}) {
    MlpConfig config{5, 3, 8, 2, activation};
    Mlp<double> mlp(config, 7);
    const Matrix input = RandomMatrix(5, 6, 1, -1, 1);
    const Matrix weights = RandomMatrix(3, 6, 2, -1, 1);
    Matrix out, d_input;
    Mlp<double>::Cache cache;
    mlp.Forward(input, &out, &cache);
    std::vector<double> d_params(mlp.num_params(), 0.0);
    mlp.Backward(cache, weights, d_params.data(), &d_input);

    const double h = 1e-6;
    double worst = 0;
    for (int k = 0; k < mlp.num_params(); ++k) {
      const double saved = mlp.params()[k];
      mlp.params()[k] = saved + h;
      const double plus = MlpLoss(mlp, input, weights);
      mlp.params()[k] = saved - h;
      const double minus = MlpLoss(mlp, input, weights);
      mlp.params()[k] = saved;
      worst = std::max(worst, std::abs((plus - minus) / (2 * h) - d_params[k]));
    }
    CHECK(worst < 1e-7);
    for (Eigen::Index k = 0; k < input.size(); ++k) {
      Matrix moved = input;
      moved.data()[k] += h;
      const double plus = MlpLoss(mlp, moved, weights);
      moved.data()[k] -= 2 * h;
      const double minus = MlpLoss(mlp, moved, weights);
      CHECK(std::abs((plus - minus) / (2 * h) - d_input.data()[k]) < 1e-7);
    }
  }
}

TEST_CASE("an MLP's input gradient can stop at its first input rows, the parameters' gradient unchanged",
          "[gradients]") {
  // 19 of 31 inputs, as the colour network's geometry features before the direction encoding; in double (Eigen's
  // products) and in float (the AVX2 kernels where the build has them).
  const auto check = [](auto zero) {
    using T = decltype(zero);
    using MatrixT = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
    Mlp<T> mlp(MlpConfig{31, 3, 64, 2, OutputActivation::kSigmoid}, 7);
    const MatrixT input = RandomMatrix(31, 70, 1, -1, 1).cast<T>(), d_output = RandomMatrix(3, 70, 2, -1, 1).cast<T>();
    MatrixT out, all, first;
    typename Mlp<T>::Cache cache;
    mlp.Forward(input, &out, &cache);
    std::vector<T> d_all(mlp.num_params(), T(0)), d_first(mlp.num_params(), T(0));
    mlp.Backward(cache, d_output, d_all.data(), &all);
    mlp.Backward(cache, d_output, d_first.data(), &first, 19);
    REQUIRE(all.rows() == 31);
    REQUIRE(first.rows() == 19);
    REQUIRE(first.cols() == 70);
    // The same sums, perhaps in another order (the products' blocking depends on the shape).
    const double tolerance = sizeof(T) == 4 ? 1e-6 : 1e-14;
    CHECK((first - all.topRows(19)).cwiseAbs().maxCoeff() <= tolerance * all.cwiseAbs().maxCoeff());
    CHECK(all.topRows(19).cwiseAbs().maxCoeff() > 1e-3);
    CHECK(d_first == d_all);
  };
  check(0.0);
  check(0.0f);
}

TEST_CASE("sigmoid output stays finite and saturates for huge inputs", "[gradients]") {
  MlpConfig config{1, 1, 1, 0, OutputActivation::kSigmoid};
  Mlp<float> mlp(config, 1);
  mlp.params()[0] = 1;  // weight
  mlp.params()[1] = 0;  // bias
  Eigen::MatrixXf input(1, 3), out;
  input << -1e30f, 0.0f, 1e30f;
  Mlp<float>::Cache cache;
  mlp.Forward(input, &out, &cache);
  CHECK(out(0, 0) == Approx(0.0f).margin(1e-20));
  CHECK(out(0, 1) == Approx(0.5f));
  CHECK(out(0, 2) == Approx(1.0f));
  CHECK(out.allFinite());
}

TEST_CASE("hash-grid gradients match finite differences, in 2D and 3D, dense and hashed levels, 1 to 4 features",
          "[gradients]") {
  // 70 points: more than one group of points whose entries are found before they are read (hash_grid.cc).
  for (const auto& [dims, features] :
       {std::pair(2, 2), std::pair(3, 1), std::pair(3, 2), std::pair(3, 3), std::pair(3, 4)}) {
    CAPTURE(dims, features);
    HashGridConfig config = SmallGridConfig();
    config.features_per_level = features;
    HashGridEncoding<double> grid(dims, config, 3);
    const Matrix input = RandomMatrix(dims, 70, 4, 0, 1);
    const Matrix weights = RandomMatrix(grid.output_dims(), 70, 5, -1, 1);
    CHECK(CheckParameterGradients(grid, input, weights) > 0);
  }
}

TEST_CASE("hash-grid gradients with respect to the input match finite differences", "[gradients]") {
  for (const int dims : {2, 3}) {
    HashGridEncoding<double> grid(dims, SmallGridConfig(), 3);
    std::mt19937_64 random(6);
    std::uniform_real_distribution<double> uniform(-1, 1);
    for (size_t k = 0; k < grid.num_params(); ++k) grid.params()[k] = uniform(random);  // features of size 1
    Matrix input = RandomMatrix(dims, 9, 4, 0.01, 0.99);
    input(0, 8) = 1.5;  // clamped along x: no gradient there
    const Matrix weights = RandomMatrix(grid.output_dims(), 9, 5, -1, 1);
    const Matrix d_input = CheckInputGradients(grid, input, weights);
    CHECK(d_input(0, 8) == 0);
    CHECK(d_input.cwiseAbs().maxCoeff() > 1);  // features of size 1 over cells of 1/20: slopes of tens
  }
  // An encoding without an input gradient says so.
  PositionalEncoding<double> fixed(3, 2);
  Matrix d_input;
  CHECK_THROWS_AS(fixed.InputGradient(Matrix::Zero(3, 1), Matrix::Zero(15, 1), &d_input), std::logic_error);
}

TEST_CASE("the float hash grid (its own loops and layouts) agrees with the double one", "[gradients]") {
  // 600 points: several groups and blocks of the level-major scratch (hash_grid.cc); 2 and 4 features take the
  // loops compiled for them, 3 the general ones.
  for (const int features : {2, 3, 4}) {
    CAPTURE(features);
    HashGridConfig config = SmallGridConfig();
    config.features_per_level = features;
    HashGridEncoding<double> exact(3, config, 3);
    HashGridEncoding<float> grid(3, config, 3);
    std::mt19937_64 random(8);
    std::uniform_real_distribution<double> uniform(-1, 1);
    for (size_t k = 0; k < grid.num_params(); ++k) {
      grid.params()[k] = static_cast<float>(uniform(random));
      exact.params()[k] = grid.params()[k];
    }
    const Matrix input = RandomMatrix(3, 600, 4, 0, 1), d_output = RandomMatrix(exact.output_dims(), 600, 5, -1, 1);
    Matrix out;
    Eigen::MatrixXf out_float;
    exact.Forward(input, &out);
    grid.Forward(input.cast<float>(), &out_float);
    // Rows 0..features-1 are the coarsest level (dense, 2 cells a side: 4 vertices with the border), by hand.
    for (Eigen::Index i = 0; i < input.cols(); ++i) {
      const Eigen::Vector3d position = input.col(i) * 2.0, fraction = position.array() - position.array().floor();
      for (int f = 0; f < features; ++f) {
        double value = 0;
        for (int corner = 0; corner < 8; ++corner) {
          double weight = 1;
          int entry = 0;
          for (int d = 0, stride = 1; d < 3; ++d, stride *= 4) {
            const int upper = (corner >> d) & 1;
            weight *= upper ? fraction[d] : 1 - fraction[d];
            entry += (static_cast<int>(position[d]) + upper) * stride;
          }
          value += weight * exact.params()[entry * features + f];
        }
        REQUIRE(out(f, i) == Approx(value).margin(1e-12));
      }
    }
    REQUIRE(out_float.rows() == out.rows());
    REQUIRE(out_float.cols() == 600);
    CHECK((out_float.cast<double>() - out).cwiseAbs().maxCoeff() < 1e-5);
    exact.Backward(input, d_output);
    grid.Backward(input.cast<float>(), d_output.cast<float>());
    double worst = 0, largest = 0;
    for (size_t k = 0; k < grid.num_params(); ++k) {
      worst = std::max(worst, std::abs(grid.grads()[k] - exact.grads()[k]));
      largest = std::max(largest, std::abs(exact.grads()[k]));
    }
    CHECK(largest > 1);
    CHECK(worst < 1e-5 * largest);
  }
}

TEST_CASE("hash-grid interpolation reproduces vertex values and is continuous", "[gradients]") {
  HashGridConfig config;
  config.levels = 1;
  config.features_per_level = 1;
  config.log2_table_size = 10;
  config.base_resolution = 4;
  config.finest_resolution = 4;
  HashGridEncoding<double> grid(2, config, 1);
  Matrix points(2, 2), out;
  points << 0.5 - 1e-9, 0.5 + 1e-9, 0.3, 0.3;
  grid.Forward(points, &out);
  CHECK(out(0, 0) == Approx(out(0, 1)).margin(1e-12));
}

TEST_CASE("positional encoding: raw input, then sin and cos of 2^k pi x", "[encoding]") {
  PositionalEncoding<double> encoding(2, 3);
  CHECK(encoding.output_dims() == 2 * (1 + 2 * 3));
  Matrix point(2, 1), out;
  point << 0.25, 0.5;
  encoding.Forward(point, &out);
  CHECK(out(0, 0) == 0.25);
  CHECK(out(1, 0) == 0.5);
  CHECK(out(2, 0) == Approx(std::sin(M_PI * 0.25)));               // k = 0, sin, x
  CHECK(out(5, 0) == Approx(std::cos(M_PI * 0.5)).margin(1e-12));  // k = 0, cos, y
  CHECK(out(6, 0) == Approx(std::sin(2 * M_PI * 0.25)));           // k = 1, sin, x: sin(pi / 2) = 1
  CHECK(out(6, 0) == Approx(1.0));
  CHECK(PositionalEncoding<double>(2, 10).output_dims() == 42);  // the seed's 2D encoding
}

}  // namespace p2n::testing

#include "nerf/ngp_field.h"
#include "nerf/vanilla_field.h"

namespace p2n::testing {

namespace {

// Checks every dense parameter (and the trainable encoding's) of `field` against central differences of
// L = sum w_density * density + sum w_rgb * rgb.
void CheckFieldGradients(RadianceField<double>& field) {
  const Eigen::MatrixXd positions = Eigen::MatrixXd::Random(3, 5).array() * 0.5 + 0.5;
  Eigen::MatrixXd directions = Eigen::MatrixXd::Random(3, 5);
  directions.colwise().normalize();
  const Eigen::MatrixXd w_density = Eigen::MatrixXd::Random(1, 5), w_rgb = Eigen::MatrixXd::Random(3, 5);
  const auto loss = [&] {
    Eigen::MatrixXd density, rgb;
    RadianceField<double>::Cache cache;
    field.Forward(positions, directions, &density, &rgb, &cache);
    return (density.array() * w_density.array()).sum() + (rgb.array() * w_rgb.array()).sum();
  };
  Eigen::MatrixXd density, rgb, density_only, d_encoded;
  RadianceField<double>::Cache cache;
  field.Forward(positions, directions, &density, &rgb, &cache);
  field.Density(positions, &density_only);
  CHECK((density.array() >= 0).all());
  CHECK((density - density_only).norm() < 1e-12);
  std::vector<double> d_dense(field.num_dense_params(), 0.0);
  Encoding<double>* grid = field.TrainableEncoding();
  field.Backward(cache, w_density, w_rgb, d_dense.data(), &d_encoded);
  const auto check = [&](double* params, size_t count, const double* analytic) {
    const double h = 1e-6;
    double worst = 0, largest = 0;
    for (size_t k = 0; k < count; ++k) {
      const double saved = params[k];
      params[k] = saved + h;
      const double plus = loss();
      params[k] = saved - h;
      const double minus = loss();
      params[k] = saved;
      worst = std::max(worst, std::abs((plus - minus) / (2 * h) - analytic[k]));
      largest = std::max(largest, std::abs(analytic[k]));
    }
    CHECK(largest > 1e-6);
    CHECK(worst < 1e-6 * std::max(1.0, largest));
  };
  size_t offset = 0;
  for (const ParamBlock<double>& block : field.DenseParams()) {
    check(block.data, block.size, d_dense.data() + offset);
    offset += block.size;
  }
  if (grid != nullptr) {
    grid->Backward(cache.positions, d_encoded);
    check(grid->params(), grid->num_params(), grid->grads());
  }
}

}  // namespace

TEST_CASE("the ngp field's gradients (grid, density MLP, colour MLP) match finite differences", "[gradients]") {
  NgpFieldConfig config;
  config.grid.levels = 3;
  config.grid.log2_table_size = 8;
  config.grid.base_resolution = 2;
  config.grid.finest_resolution = 8;
  config.geometry_features = 3;
  config.width = 8;
  NgpField<double> field(config, 11);
  // Larger grid values than the 1e-4 initialisation, so that every path carries gradient.
  for (size_t k = 0; k < field.encoding().num_params(); ++k) field.encoding().params()[k] = 0.5 * std::sin(1.7 * k);
  CheckFieldGradients(field);
}

TEST_CASE("the ngp field on planes: gradients (planes, density MLP, colour MLP) match finite differences",
          "[gradients]") {
  NgpFieldConfig config;
  config.planes = PlaneGridConfig{.levels = 2, .features_per_level = 3, .finest_resolution = 4, .depth_resolution = 2};
  config.geometry_features = 3;
  config.width = 8;
  NgpField<double> field(config, 11);
  CheckFieldGradients(field);
}

TEST_CASE("the vanilla field's gradients (both halves, skip connection, heads) match finite differences",
          "[gradients]") {
  VanillaFieldConfig config;
  config.position_levels = 2;
  config.direction_levels = 1;
  config.width = 8;
  config.layers = 4;
  config.colour_width = 4;
  VanillaField<double> field(config, 3);
  // Positive density head bias, so that the ReLU density passes gradient.
  field.DenseParams()[2].data[field.DenseParams()[2].size - 1 - config.width] = 2.0;
  CheckFieldGradients(field);
}

TEST_CASE("the vanilla field is the seed's model: its sizes and its config round trip", "[gradients]") {
  VanillaField<float> field(VanillaFieldConfig{}, 0);
  // 63 -> 256 x4, (256 + 63) -> 256 x4, 256 -> 1 + 256, (256 + 27) -> 128 -> 3.
  const size_t expected = (63 * 256 + 256) + 3 * (256 * 256 + 256) + (319 * 256 + 256) + 3 * (256 * 256 + 256) +
                          (256 * 257 + 257) + (283 * 128 + 128) + (128 * 3 + 3);
  CHECK(field.num_dense_params() == expected);
  const auto copy = MakeField<float>(field.Config(), 0);
  CHECK(copy->Config() == field.Config());
  CHECK_THROWS_AS(MakeField<float>(nlohmann::json{{"otype", "Unknown"}}, 0), std::invalid_argument);
}

TEST_CASE("the ngp field's density stays finite for huge raw outputs", "[gradients]") {
  NgpFieldConfig config;
  config.grid.levels = 2;
  config.grid.log2_table_size = 6;
  config.grid.finest_resolution = 32;
  NgpField<float> field(config, 1);
  for (int k = 0; k < field.density_mlp().num_params(); ++k) field.density_mlp().params()[k] = 1e3f;
  for (size_t k = 0; k < field.encoding().num_params(); ++k) field.encoding().params()[k] = 10.0f;
  Eigen::MatrixXf positions = Eigen::MatrixXf::Constant(3, 2, 0.5f), directions(3, 2), density, rgb;
  directions << 0, 1, 0, 0, 1, 0;
  NgpField<float>::Cache cache;
  field.Forward(positions, directions, &density, &rgb, &cache);
  CHECK(density.allFinite());
  CHECK(density(0, 0) == Approx(std::exp(15.0f)));
  CHECK(rgb.allFinite());
}

}  // namespace p2n::testing
