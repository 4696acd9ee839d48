#pragma once
// Checks shared by the encodings' tests: their gradients against central finite differences, in double precision,
// of the loss L = sum(weights .* encoding(input)).

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "nerf/encoding.h"

namespace p2n::testing {

inline Eigen::MatrixXd RandomMatrix(int rows, int cols, uint64_t seed, double low, double high) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(low, high);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(random);
  return m;
}

inline double EncodingLoss(const Encoding<double>& encoding, const Eigen::MatrixXd& input,
                           const Eigen::MatrixXd& weights) {
  Eigen::MatrixXd out;
  encoding.Forward(input, &out);
  return (out.array() * weights.array()).sum();
}

// dL/d(params) from Backward() against finite differences (within 1e-8), every entry with a gradient marked for the
// sparse Adam step, Backward() adding until ZeroGrad() clears it. Returns how many parameters have a gradient.
inline size_t CheckParameterGradients(Encoding<double>& encoding, const Eigen::MatrixXd& input,
                                      const Eigen::MatrixXd& weights) {
  encoding.Backward(input, weights);
  const size_t count = encoding.num_params();
  double* params = encoding.params();
  const std::vector<double> analytic(encoding.grads(), encoding.grads() + count);
  for (size_t k = 0; k < count; ++k) {
    if (analytic[k] != 0) REQUIRE(encoding.touched()->marked(k / encoding.entry_size() / TouchMarks::kGroupEntries));
  }
  const double h = 1e-6;
  double worst = 0;
  size_t nonzero = 0;
  for (size_t k = 0; k < count; ++k) {
    const double saved = params[k];
    params[k] = saved + h;
    const double plus = EncodingLoss(encoding, input, weights);
    params[k] = saved - h;
    const double minus = EncodingLoss(encoding, input, weights);
    params[k] = saved;
    const double numeric = (plus - minus) / (2 * h);
    worst = std::max(worst, std::abs(numeric - analytic[k]));
    nonzero += std::abs(numeric) > 1e-9;
  }
  CHECK(worst < 1e-8);
  encoding.Backward(input, weights);
  for (size_t k = 0; k < count; ++k) CHECK(encoding.grads()[k] == Approx(2 * analytic[k]).margin(1e-12));
  encoding.ZeroGrad();
  CHECK(std::all_of(encoding.grads(), encoding.grads() + count, [](double g) { return g == 0; }));
  return nonzero;
}

// dL/d(input) from InputGradient() against finite differences (within 1e-6); returns it.
inline Eigen::MatrixXd CheckInputGradients(const Encoding<double>& encoding, const Eigen::MatrixXd& input,
                                           const Eigen::MatrixXd& weights) {
  Eigen::MatrixXd d_input;
  encoding.InputGradient(input, weights, &d_input);
  REQUIRE(d_input.rows() == input.rows());
  REQUIRE(d_input.cols() == input.cols());
  const double h = 1e-7;
  for (Eigen::Index k = 0; k < input.size(); ++k) {
    Eigen::MatrixXd moved = input;
    moved.data()[k] += h;
    const double plus = EncodingLoss(encoding, moved, weights);
    moved.data()[k] -= 2 * h;
    const double numeric = (plus - EncodingLoss(encoding, moved, weights)) / (2 * h);
    CHECK(d_input.data()[k] == Approx(numeric).margin(1e-6));
  }
  return d_input;
}

}  // namespace p2n::testing
