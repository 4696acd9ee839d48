// The networks' rendering pass (bfloat16 products with AVX-512 BF16, float ones with AVX2) against Mlp's float
// pass: exact where every input and weight is a bfloat16 (and every sum exact in float), within a percent of the
// output's scale otherwise, and the field's Render() against its Forward().

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "nerf/ngp_field.h"
#include "nerf/render_mlp.h"

using namespace p2n;

namespace {

// Rounds every weight and bias to eighths (exact in bfloat16; sums of their products are exact in float).
void MakeWeightsCoarse(Mlp<float>* mlp) {
  for (int i = 0; i < mlp->num_params(); ++i) mlp->params()[i] = std::round(8 * mlp->params()[i]) / 8;
}

}  // namespace

TEST_CASE("rendering networks: the float pass's outputs, exactly where bfloat16 holds the numbers", "[render_mlp]") {
  if (!RenderMlp::Available()) {
    WARN("neither AVX-512 BF16 nor AVX2 in this build: nothing to compare");
    return;
  }
  INFO("instructions: " << RenderMlp::Instructions());
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> eighths(-8, 8);
  // One layer (its sums are of exact products, so exact in float), at odd sizes: an odd input count, outputs that
  // fill no row block, more than four row blocks; and a last block of samples that fills no tile.
  for (const MlpConfig config :
       {MlpConfig{31, 3, 64, 0, OutputActivation::kSigmoid}, MlpConfig{32, 16, 64, 0, OutputActivation::kNone},
        MlpConfig{5, 80, 64, 0, OutputActivation::kRelu}}) {
    Mlp<float> mlp(config, 3);
    MakeWeightsCoarse(&mlp);
    const Eigen::Index n = 2 * 192 + 7;
    Eigen::MatrixXf input(config.inputs, n);
    for (float& v : input.reshaped()) v = eighths(rng) / 8.0f;
    Eigen::MatrixXf expected, output(config.outputs, n);
    Mlp<float>::Cache cache;
    mlp.Forward(input, &expected, &cache);
    RenderMlp(mlp).Forward(input.data(), n, output.data());
    INFO("inputs " << config.inputs << ", outputs " << config.outputs);
    CHECK(output == expected);
  }
}

TEST_CASE("rendering networks: within a percent of the float pass through hidden layers", "[render_mlp]") {
  if (!RenderMlp::Available()) {
    WARN("neither AVX-512 BF16 nor AVX2 in this build: nothing to compare");
    return;
  }
  INFO("instructions: " << RenderMlp::Instructions());
  Mlp<float> mlp({32, 16, 64, 1, OutputActivation::kNone}, 7);
  const Eigen::MatrixXf input = Eigen::MatrixXf::Random(32, 1000);
  Eigen::MatrixXf expected, output(16, 1000);
  Mlp<float>::Cache cache;
  mlp.Forward(input, &expected, &cache);
  RenderMlp(mlp).Forward(input.data(), input.cols(), output.data());
  const float scale = expected.cwiseAbs().maxCoeff();
  // bfloat16 keeps 8 bits of each value; float products differ from Mlp's only in the order of their sums.
  CHECK((output - expected).cwiseAbs().maxCoeff() < (RenderMlp::Rounds() ? 0.01f : 1e-5f) * scale);
  if (RenderMlp::Rounds()) CHECK((output - expected).cwiseAbs().maxCoeff() > 0);  // it did round
}

TEST_CASE("a field's rendering pass agrees with its training pass", "[render_mlp]") {
  NgpFieldConfig config;
  config.grid.log2_table_size = 12;
  NgpField<float> field(config, 11);
  for (int i = 0; i < 50; ++i) {  // features beyond the initial +-1e-4, so that the networks see real inputs
    field.encoding().params()[i * 37 % field.encoding().num_params()] = 0.5f * std::sin(float(i));
  }
  const Eigen::MatrixXf positions = (Eigen::MatrixXf::Random(3, 500).array() + 1) / 2;
  Eigen::MatrixXf directions = Eigen::MatrixXf::Random(3, 500);
  directions.colwise().normalize();
  Eigen::MatrixXf density, rgb, render_density, render_rgb;
  RadianceField<float>::Cache cache;
  field.Forward(positions, directions, &density, &rgb, &cache);
  field.Render(positions, directions, &render_density, &render_rgb);
  REQUIRE(render_density.cols() == 500);
  CHECK(((render_density - density).array().abs() <= 0.02f * density.array() + 1e-6f).all());
  CHECK((render_rgb - rgb).cwiseAbs().maxCoeff() < 2e-3f);
}
