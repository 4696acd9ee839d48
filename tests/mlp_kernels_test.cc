// The training passes' layer products (AVX2 and FMA) against Eigen's in double, at the shapes that exercise their
// edges: rows that fill no 8-row block, more than one 16-row tile, column counts that leave every remainder of the
// 6-wide tiles, more samples than one gradient block.

#include <catch2/catch.hpp>

#include <random>

#include "nerf/mlp_kernels.h"

using namespace p2n;

namespace {

Eigen::MatrixXf UniformMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937* rng) {
  std::uniform_real_distribution<float> uniform(-1, 1);
  Eigen::MatrixXf m(rows, cols);
  for (float& v : m.reshaped()) v = uniform(*rng);
  return m;
}

// Largest absolute difference, relative to the largest magnitude of `expected`.
double RelativeError(const Eigen::MatrixXf& actual, const Eigen::MatrixXd& expected) {
  return (actual.cast<double>() - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff();
}

struct Shape {
  int m, k;
  Eigen::Index n;
};

}  // namespace

TEST_CASE("mlp kernels: a layer's forward pass, input gradient and parameter gradients", "[mlp]") {
  if (!mlp_kernels::Available()) {
    WARN("no AVX2 and FMA in this build: Mlp uses Eigen's products");
    return;
  }
  std::mt19937 rng(11);
  for (const Shape shape : {Shape{64, 32, 1000}, Shape{3, 31, 7}, Shape{16, 64, 300}, Shape{80, 5, 13}, Shape{9, 64, 1},
                            Shape{64, 64, 517}}) {
    INFO("m " << shape.m << ", k " << shape.k << ", n " << shape.n);
    const Eigen::MatrixXf w = UniformMatrix(shape.m, shape.k, &rng), x = UniformMatrix(shape.k, shape.n, &rng),
                          dy = UniformMatrix(shape.m, shape.n, &rng);
    const Eigen::VectorXf b = UniformMatrix(shape.m, 1, &rng);
    const Eigen::MatrixXd wd = w.cast<double>(), xd = x.cast<double>(), dyd = dy.cast<double>();

    const Eigen::MatrixXd affine = (wd * xd).colwise() + b.cast<double>();
    Eigen::MatrixXf y(shape.m, shape.n);
    mlp_kernels::LayerForward(w.data(), b.data(), shape.m, shape.k, x.data(), shape.n, false, y.data());
    CHECK(RelativeError(y, affine) < 1e-5);
    mlp_kernels::LayerForward(w.data(), b.data(), shape.m, shape.k, x.data(), shape.n, true, y.data());
    CHECK(RelativeError(y, affine.cwiseMax(0.0)) < 1e-5);
    CHECK((y.array() >= 0).all());

    const Eigen::MatrixXd back = wd.transpose() * dyd;
    Eigen::MatrixXf dx(shape.k, shape.n);
    mlp_kernels::LayerInputGradient(w.data(), shape.m, shape.k, dy.data(), shape.n, nullptr, dx.data());
    CHECK(RelativeError(dx, back) < 1e-5);
    mlp_kernels::LayerInputGradient(w.data(), shape.m, shape.k, dy.data(), shape.n, x.data(), dx.data());
    CHECK(RelativeError(dx, (xd.array() > 0).select(back, 0.0)) < 1e-5);
    CHECK((x.array() > 0 || dx.array() == 0).all());

    // Added to what is there.
    const Eigen::MatrixXf w0 = UniformMatrix(shape.m, shape.k, &rng);
    const Eigen::VectorXf b0 = UniformMatrix(shape.m, 1, &rng);
    Eigen::MatrixXf dw = w0;
    Eigen::VectorXf db = b0;
    mlp_kernels::AddLayerGradient(dy.data(), shape.m, x.data(), shape.k, shape.n, dw.data(), db.data());
    CHECK(RelativeError(dw, w0.cast<double>() + dyd * xd.transpose()) < 1e-5);
    CHECK(RelativeError(db, b0.cast<double>() + dyd.rowwise().sum()) < 1e-5);
  }
}
