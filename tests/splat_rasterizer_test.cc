// The splat rasterizer: analytic values, gradients against central finite differences in double precision, and
// finite results for degenerate Gaussians.

#include <catch2/catch.hpp>

#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <random>

#include "splat/rasterizer.h"
#include "test_camera.h"

namespace p2n::testing {
namespace {

// A camera at `position` looking at the origin, `width` x `height` pixels, focal length `focal` pixels.
PinholeCamera LookingAtOrigin(int width, int height, double focal, const Eigen::Vector3d& position) {
  PinholeCamera camera = CentredCamera(width, height, focal);
  camera.world_from_cam = LookAtPose(position, Eigen::Vector3d::Zero());
  return camera;
}

// `count` Gaussians near the origin with random shapes, rotations, opacities and colours of degree `degree`.
Gaussians<double> RandomGaussians(int count, int degree, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1, 1);
  Gaussians<double> g;
  g.sh_degree = degree;
  g.Resize(count);
  for (int i = 0; i < count; ++i) {
    for (int a = 0; a < 3; ++a) g.positions[3 * i + a] = 0.5 * uniform(random);
    for (int a = 0; a < 3; ++a) g.log_scales[3 * i + a] = std::log(0.15) + 0.4 * uniform(random);
    for (int a = 0; a < 4; ++a) g.rotations[4 * i + a] = uniform(random) + (a == 0 ? 1.5 : 0);
    g.opacity_logits[i] = 1.5 * uniform(random);
    for (int c = 0; c < 3; ++c) g.sh_dc[3 * i + c] = uniform(random);
    const int rest = 3 * (g.coefficients() - 1);
    for (int k = 0; k < rest; ++k) g.sh_rest[rest * i + k] = 0.2 * uniform(random);
  }
  return g;
}

// L = Σ weight · rgb.
double Loss(const Gaussians<double>& g, const PinholeCamera& camera, const RasterOptions& options,
            const std::vector<double>& weights) {
  Rasterizer<double> rasterizer;
  rasterizer.Forward(g, camera, options);
  double loss = 0;
  for (size_t k = 0; k < weights.size(); ++k) loss += weights[k] * rasterizer.rgb()[k];
  return loss;
}

// Every parameter's derivative in `grads` against central differences (step 1e-6) of loss() as `g` changes.
template <class Loss>
void CheckAgainstCentralDifferences(Gaussians<double>* g, const Gaussians<double>& grads, const Loss& loss,
                                    double margin, double epsilon) {
  std::vector<std::vector<double>*> params;
  std::vector<const std::vector<double>*> analytic;
  g->ForEachArray([&](std::vector<double>& v, int) { params.push_back(&v); });
  grads.ForEachArray([&](const std::vector<double>& v, int) { analytic.push_back(&v); });
  for (size_t a = 0; a < params.size(); ++a) {
    for (size_t k = 0; k < params[a]->size(); ++k) {
      double& value = (*params[a])[k];
      const double saved = value, h = 1e-6;
      value = saved + h;
      const double plus = loss();
      value = saved - h;
      const double minus = loss();
      value = saved;
      INFO("array " << a << " value " << k);
      CHECK((*analytic[a])[k] == Approx((plus - minus) / (2 * h)).margin(margin).epsilon(epsilon));
    }
  }
}

}  // namespace

TEST_CASE("A splat's centre pixel blends its colour by its opacity over the background", "[splat]") {
  const PinholeCamera camera = LookingAtOrigin(32, 32, 40, {0, 0, 4});
  Gaussians<double> g;
  g.sh_degree = 0;
  g.Resize(1);
  g.rotations[0] = 1;
  const double sigma = 0.05;
  for (int a = 0; a < 3; ++a) g.log_scales[a] = std::log(sigma);
  g.opacity_logits[0] = Logit(0.6);
  const double colour[3] = {0.9, 0.2, 0.4};
  for (int c = 0; c < 3; ++c) g.sh_dc[c] = (colour[c] - 0.5) / kShC0;
  RasterOptions options;
  options.background = {0.1, 0.3, 0.5};
  Rasterizer<double> rasterizer;
  rasterizer.Forward(g, camera, options);

  // The mean projects to (16, 16), a pixel corner; pixel (16, 16)'s centre is half a pixel off in x and y.
  // The 2D variance is (sigma · focal / depth)² + 0.3 in each axis.
  const double variance = std::pow(sigma * 40 / 4, 2) + 0.3;
  const double alpha = 0.6 * std::exp(-0.5 * (0.25 + 0.25) / variance);
  const size_t pixel = 16 * 32 + 16;
  for (int c = 0; c < 3; ++c) {
    CHECK(rasterizer.rgb()[3 * pixel + c] == Approx(alpha * colour[c] + (1 - alpha) * options.background[c]));
  }
  CHECK(rasterizer.transmittance()[pixel] == Approx(1 - alpha));
  CHECK(rasterizer.transmittance()[0] == 1.0);  // a corner, 16 pixels away: skipped as alpha < 1/255
  CHECK(rasterizer.drawn() == 1);
}

TEST_CASE("A faint or thin splat is listed only in the tiles where it is blended, and blended in all of them",
          "[splat]") {
  // One splat stretched along the image's diagonal: its 3-sigma square covers every tile, its ellipse far fewer.
  const PinholeCamera camera = LookingAtOrigin(128, 128, 100, {0, 0, 4});
  Gaussians<double> g;
  g.sh_degree = 0;
  g.Resize(1);
  g.rotations[0] = std::cos(M_PI / 8), g.rotations[3] = std::sin(M_PI / 8);  // 45 degrees about the view axis
  g.log_scales[0] = std::log(0.8), g.log_scales[1] = g.log_scales[2] = std::log(0.02);
  for (int c = 0; c < 3; ++c) g.sh_dc[c] = 0.3;
  size_t previous_entries = 8 * 8 + 1;  // the 3-sigma square: every tile
  for (const double opacity : {0.99, 0.02}) {
    INFO("opacity " << opacity);
    g.opacity_logits[0] = Logit(opacity);
    Rasterizer<double> rasterizer;
    rasterizer.Forward(g, camera, RasterOptions{});
    CHECK(rasterizer.drawn() == 1);
    CHECK(rasterizer.tile_entries() < previous_entries);
    previous_entries = rasterizer.tile_entries();
    // Every pixel against the splat's alpha there, drawn from the same projection (ignoring the tiles).
    Splat2D<double> s;
    double depth = 0, radius = 0;
    REQUIRE(ProjectGaussian(g, 0, SplatCamera<double>::From(camera), RasterOptions{}.projection, &s, &depth, &radius));
    int blended = 0;
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const double dx = s.x - (x + 0.5), dy = s.y - (y + 0.5);
        const double power = -0.5 * (s.conic_a * dx * dx + s.conic_c * dy * dy) - s.conic_b * dx * dy;
        const double alpha = std::min(opacity * std::exp(power), 0.99);
        const double expected = alpha >= 1.0 / 255 ? alpha : 0.0;
        blended += expected > 0;
        INFO("pixel " << x << ", " << y);
        REQUIRE(1 - rasterizer.transmittance()[y * camera.width + x] == Approx(expected).margin(1e-12));
      }
    }
    CHECK(blended > 100);
  }
}

TEST_CASE("Opaque splats hide what lies behind them, whatever their order in memory", "[splat]") {
  const PinholeCamera camera = LookingAtOrigin(16, 16, 20, {0, 0, 4});
  Gaussians<double> g;
  g.sh_degree = 0;
  g.Resize(2);
  for (int i = 0; i < 2; ++i) {
    g.rotations[4 * i] = 1;
    for (int a = 0; a < 3; ++a) g.log_scales[3 * i + a] = std::log(1.0);
    g.opacity_logits[i] = 20;  // alpha capped at 0.99
  }
  g.positions[2] = -1;  // the first is farther from the camera at z = 4
  g.positions[5] = 1;
  for (int c = 0; c < 3; ++c) g.sh_dc[c] = (0.0 - 0.5) / kShC0, g.sh_dc[3 + c] = (1.0 - 0.5) / kShC0;
  Rasterizer<double> rasterizer;
  rasterizer.Forward(g, camera, RasterOptions{});
  // Front: 0.99 of white; behind it 0.99 of the remaining 0.01 is black.
  CHECK(rasterizer.rgb()[3 * (8 * 16 + 8)] == Approx(0.99).epsilon(1e-3));
}

TEST_CASE("Projection gradients match finite differences", "[splat][gradients]") {
  const PinholeCamera camera = LookingAtOrigin(64, 48, 50, {0.3, -0.2, 3});
  const SplatCamera<double> view = SplatCamera<double>::From(camera);
  const ProjectionOptions options;
  Gaussians<double> g = RandomGaussians(4, 3, 11);
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (size_t i = 0; i < g.size(); ++i) {
    Splat2D<double> weight;
    weight.x = uniform(random), weight.y = uniform(random), weight.conic_a = uniform(random);
    weight.conic_b = uniform(random), weight.conic_c = uniform(random), weight.opacity = uniform(random);
    for (double& c : weight.rgb) c = uniform(random);
    const auto loss = [&] {
      Splat2D<double> s;
      double depth, radius;
      REQUIRE(ProjectGaussian(g, i, view, options, &s, &depth, &radius));
      return weight.x * s.x + weight.y * s.y + weight.conic_a * s.conic_a + weight.conic_b * s.conic_b +
             weight.conic_c * s.conic_c + weight.opacity * s.opacity + weight.rgb[0] * s.rgb[0] +
             weight.rgb[1] * s.rgb[1] + weight.rgb[2] * s.rgb[2];
    };
    Gaussians<double> grads = g;
    grads.SetZero();
    ProjectGaussianBackward(g, i, view, options, weight, &grads);
    INFO("gaussian " << i);
    CheckAgainstCentralDifferences(&g, grads, loss, 1e-6, 1e-5);
  }
}

TEST_CASE("Rasterizer gradients match finite differences", "[splat][gradients]") {
  // Three tiles by two (the last column 5 pixels wide: part of a strip of lanes), a background, overlapping
  // Gaussians of degree 3 seen off-centre.
  const PinholeCamera camera = LookingAtOrigin(37, 30, 30, {0.4, 0.3, 3});
  RasterOptions options;
  options.background = {0.2, 0.5, 0.7};
  Gaussians<double> g = RandomGaussians(12, 3, 3);
  std::mt19937_64 random(9);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::vector<double> weights(37 * 30 * 3);
  for (double& w : weights) w = uniform(random);

  Rasterizer<double> rasterizer;
  rasterizer.Forward(g, camera, options);
  REQUIRE(rasterizer.drawn() == g.size());
  Gaussians<double> grads = g;
  grads.SetZero();
  rasterizer.Backward(weights, &grads);

  CheckAgainstCentralDifferences(
      &g, grads, [&] { return Loss(g, camera, options, weights); }, 1e-5, 1e-4);
}

TEST_CASE("The rasterizer's gradients are the same whatever the number of threads", "[splat]") {
  // Many tiles, each splat in several: with per-thread sums the last bits would depend on who took which tile.
  const PinholeCamera camera = LookingAtOrigin(160, 128, 150, {0.4, 0.3, 3});
  const Gaussians<double> g = RandomGaussians(200, 1, 5);
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::vector<double> weights(160 * 128 * 3);
  for (double& w : weights) w = uniform(random);
  const auto gradients = [&](int threads) {
    Gaussians<double> grads = g;
    grads.SetZero();
    tbb::task_arena(threads).execute([&] {
      Rasterizer<double> rasterizer;
      rasterizer.Forward(g, camera, RasterOptions{});
      rasterizer.Backward(weights, &grads);
    });
    return grads;
  };
  const Gaussians<double> one = gradients(1);
  for (const int threads : {2, 4}) {
    const Gaussians<double> many = gradients(threads);
    std::vector<const std::vector<double>*> expected;
    one.ForEachArray([&](const std::vector<double>& values, int) { expected.push_back(&values); });
    size_t array = 0;
    many.ForEachArray([&](const std::vector<double>& values, int) {
      INFO(threads << " threads, array " << array);
      CHECK(values == *expected.at(array++));
    });
  }
}

TEST_CASE("The float rasterizer (its vector exponential and lane tests) agrees with the double one", "[splat]") {
  // Many tiles and overlapping splats, so that strips end early, skip splats and stop at the transmittance floor.
  const PinholeCamera camera = LookingAtOrigin(160, 128, 150, {0.4, 0.3, 3});
  RasterOptions options;
  options.background = {0.2, 0.5, 0.7};
  const Gaussians<double> g = RandomGaussians(300, 1, 7);
  Gaussians<float> f;
  f.sh_degree = g.sh_degree;
  f.Resize(g.size());
  std::vector<const std::vector<double>*> from;
  g.ForEachArray([&](const std::vector<double>& values, int) { from.push_back(&values); });
  size_t array = 0;
  f.ForEachArray([&](std::vector<float>& values, int) {
    const std::vector<double>& source = *from.at(array++);
    values.assign(source.begin(), source.end());
  });
  std::mt19937_64 random(13);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::vector<double> weights(160 * 128 * 3);
  for (double& w : weights) w = uniform(random);
  const std::vector<float> float_weights(weights.begin(), weights.end());

  Rasterizer<double> exact;
  exact.Forward(g, camera, options);
  Rasterizer<float> fast;
  fast.Forward(f, camera, options);
  double worst = 0;
  for (size_t k = 0; k < weights.size(); ++k) worst = std::max(worst, std::abs(exact.rgb()[k] - fast.rgb()[k]));
  CHECK(worst < 1e-4);

  Gaussians<double> exact_grads = g;
  exact_grads.SetZero();
  exact.Backward(weights, &exact_grads);
  Gaussians<float> fast_grads = f;
  fast_grads.SetZero();
  fast.Backward(float_weights, &fast_grads);
  std::vector<const std::vector<double>*> expected;
  exact_grads.ForEachArray([&](const std::vector<double>& values, int) { expected.push_back(&values); });
  array = 0;
  fast_grads.ForEachArray([&](const std::vector<float>& values, int) {
    const std::vector<double>& want = *expected.at(array++);
    double difference = 0, norm = 0;
    for (size_t k = 0; k < want.size(); ++k) {
      difference += (values[k] - want[k]) * (values[k] - want[k]);
      norm += want[k] * want[k];
    }
    INFO("array " << array - 1);
    CHECK(norm > 0);
    CHECK(std::sqrt(difference) <= 1e-3 * std::sqrt(norm));
  });
}

TEST_CASE("Degenerate splats render and differentiate to finite values", "[splat]") {
  const PinholeCamera camera = LookingAtOrigin(32, 32, 30, {0, 0, 3});
  Gaussians<double> g = RandomGaussians(8, 3, 21);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (int a = 0; a < 3; ++a) g.log_scales[a] = -inf;      // zero scale: a point, dilated to a pixel
  for (int a = 0; a < 3; ++a) g.log_scales[3 + a] = 60;    // enormous
  g.positions[3 * 2 + 2] = 3;                              // on the camera's plane
  g.positions[3 * 3 + 2] = 10;                             // behind the camera
  for (int a = 0; a < 4; ++a) g.rotations[4 * 4 + a] = 0;  // no rotation: drawn unrotated
  g.rotations[4 * 5 + 1] = nan;                            // not a number
  g.positions[3 * 6] = inf;
  g.log_scales[3 * 7] = 5, g.log_scales[3 * 7 + 1] = -30;  // a needle: its covariance is nearly singular
  Rasterizer<double> rasterizer;
  rasterizer.Forward(g, camera, RasterOptions{});
  for (const double v : rasterizer.rgb()) REQUIRE(std::isfinite(v));
  std::vector<double> ones(rasterizer.rgb().size(), 1.0);
  Gaussians<double> grads = g;
  grads.SetZero();
  rasterizer.Backward(ones, &grads);
  grads.ForEachArray([](const std::vector<double>& values, int) {
    for (const double v : values) REQUIRE(std::isfinite(v));
  });
  CHECK(rasterizer.drawn() < g.size());  // behind, on the plane, infinite: not drawn
}

TEST_CASE("A crop's camera renders the same pixels as the full view", "[splat]") {
  const PinholeCamera full = LookingAtOrigin(48, 40, 45, {0.2, 0.1, 3});
  PinholeCamera crop = full;
  crop.width = 20, crop.height = 14;
  // Pixels (16..35, 16..29) of the full view: the crop's tiles are the full view's (a splat's tail beyond its
  // 3-sigma square is drawn where its square's tiles reach, so unaligned crops differ by up to 1/255).
  crop.cx -= 16, crop.cy -= 16;
  const Gaussians<double> g = RandomGaussians(10, 1, 8);
  Rasterizer<double> a, b;
  a.Forward(g, full, RasterOptions{});
  b.Forward(g, crop, RasterOptions{});
  double worst = 0;
  for (int y = 0; y < crop.height; ++y) {
    for (int x = 0; x < crop.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        worst = std::max(
            worst, std::abs(b.rgb()[3 * (y * crop.width + x) + c] - a.rgb()[3 * ((y + 16) * full.width + x + 16) + c]));
      }
    }
  }
  CHECK(worst < 1e-9);
}

}  // namespace p2n::testing
