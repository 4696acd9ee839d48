// Volume rendering numerics (issue 4): analytic answers, stiff and extreme inputs, gradients against finite
// differences in double precision.

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "nerf/volume_rendering.h"
#include "tests/segment_ray.h"

namespace p2n::testing {
namespace {

// A ray of n equal segments over [0, length) with the given density and colour per segment.
SegmentRay UniformRay(size_t n, double length, double density, const std::array<double, 3>& colour) {
  SegmentRay ray;
  for (size_t i = 0; i < n; ++i) {
    ray.sigma.push_back(density);
    ray.rgb.insert(ray.rgb.end(), colour.begin(), colour.end());
    ray.delta.push_back(length / n);
    ray.t.push_back((i + 0.5) * length / n);
  }
  return ray;
}

const double kWhite[3] = {1, 1, 1};
const double kBlack[3] = {0, 0, 0};

}  // namespace

TEST_CASE("constant density over length d gives opacity 1 - exp(-sigma d), at any sampling", "[render]") {
  for (const size_t n : {1u, 7u, 64u, 4096u}) {
    for (const double sigma : {0.0, 1e-3, 0.7, 5.0, 1e3}) {
      const SegmentRay ray = UniformRay(n, 2.0, sigma, {0.2, 0.4, 0.6});
      const CompositeResult<double> result = Composite(ray.segments(), kBlack, 0.0);
      const double opacity = 1 - std::exp(-sigma * 2.0);
      CHECK(result.opacity == Approx(opacity).margin(1e-12));
      CHECK(result.rgb[1] == Approx(0.4 * opacity).margin(1e-12));
    }
  }
}

TEST_CASE("the median depth is the sample where the opacity first reaches one half", "[render]") {
  // Constant density: the opacity reaches 1/2 at t = ln 2 / sigma; the sample there is the one whose segment
  // holds it (segments of 0.01 from 0).
  const SegmentRay ray = UniformRay(400, 4.0, 1.0, {1, 1, 1});
  const CompositeResult<double> result = Composite(ray.segments(), kBlack, 0.0);
  CHECK(result.median_depth == Approx(std::log(2.0)).margin(0.01));
  // Haze (opacity 0.2) in front of a wall: the expected depth is pulled forward, the median is at the wall.
  SegmentRay haze_and_wall;
  haze_and_wall.sigma = {-std::log(0.8), 50.0};
  haze_and_wall.rgb = {1, 1, 1, 1, 1, 1};
  haze_and_wall.t = {1.0, 3.0};
  haze_and_wall.delta = {1.0, 1.0};
  const CompositeResult<double> wall = Composite(haze_and_wall.segments(), kBlack, 0.0);
  CHECK(wall.median_depth == 3.0);
  CHECK(wall.depth / wall.opacity < 2.7);
  // Never half opaque: none.
  CHECK(Composite(UniformRay(10, 1.0, 0.1, {1, 1, 1}).segments(), kBlack, 0.0).median_depth == -1.0);
}

TEST_CASE("a ray through empty space returns the background exactly", "[render]") {
  const double background[3] = {0.25, 0.5, 0.75};
  const SegmentRay ray = UniformRay(100, 3.0, 0.0, {1, 0, 0});
  const CompositeResult<double> result = Composite(ray.segments(), background, 1e-4);
  CHECK(result.rgb[0] == 0.25);
  CHECK(result.rgb[1] == 0.5);
  CHECK(result.rgb[2] == 0.75);
  CHECK(result.opacity == 0.0);
  // No samples at all (a ray that misses the box; near == far): the background too.
  const RaySegments<double> none{nullptr, nullptr, nullptr, nullptr, 0};
  CHECK(Composite(none, background, 1e-4).rgb[2] == 0.75);
}

TEST_CASE("densities 0..1e8 and step sizes 1e-9..1e3 give finite results in [0, 1]", "[render]") {
  for (const double sigma : {0.0, 1e-9, 1.0, 1e4, 1e8}) {
    for (const double step : {1e-9, 1e-6, 1e-2, 1.0, 1e3}) {
      for (const size_t n : {1u, 2u, 1000u}) {
        const SegmentRay ray = UniformRay(n, step * n, sigma, {1, 1, 1});
        const CompositeResult<double> result = Composite(ray.segments(), kBlack, 1e-4);
        INFO("sigma " << sigma << " step " << step << " n " << n);
        CHECK(std::isfinite(result.rgb[0]));
        CHECK(result.opacity >= 0.0);
        CHECK(result.opacity <= 1.0);
        CHECK(result.rgb[0] == Approx(result.opacity).margin(1e-12));  // white samples over black
        std::vector<double> d_sigma(n), d_rgb(3 * n);
        const double d_colour[3] = {1, 1, 1};
        CompositeBackward(ray.segments(), kBlack, result, d_colour, 1.0, 1.0, d_sigma.data(), d_rgb.data());
        for (double g : d_sigma) CHECK(std::isfinite(g));
      }
    }
  }
  // Negative and NaN densities count as empty space.
  SegmentRay ray = UniformRay(3, 1.0, -5.0, {1, 0, 0});
  ray.sigma[1] = std::nan("");
  CHECK(Composite(ray.segments(), kWhite, 0.0).rgb[1] == 1.0);
}

TEST_CASE("a thin stiff slab (sigma 1e6) composites exactly at every step size, explicit Euler does not", "[render]") {
  // The slab: density 1e6 over [0.5 - 0.5e-6, 0.5 + 0.5e-6) (optical depth 1), colour (1, 0, 0); black behind.
  const double slab_sigma = 1e6, slab_begin = 0.5 - 0.5e-6, slab_end = 0.5 + 0.5e-6;
  const double expected = 1 - std::exp(-1.0);
  for (const double step : {1e-6, 1e-5, 1e-3, 1e-1, 1.0}) {
    // Each segment carries the exact mean density of the slab inside it: piecewise-constant density.
    SegmentRay ray;
    for (double a = 0; a < 1.0 - 1e-12; a += step) {
      const double b = std::min(a + step, 1.0);
      const double overlap = std::max(0.0, std::min(b, slab_end) - std::max(a, slab_begin));
      ray.sigma.push_back(slab_sigma * overlap / (b - a));
      ray.rgb.insert(ray.rgb.end(), {1, 0, 0});
      ray.delta.push_back(b - a);
      ray.t.push_back(0.5 * (a + b));
    }
    const CompositeResult<double> result = Composite(ray.segments(), kBlack, 0.0);
    INFO("step " << step);
    CHECK(result.opacity == Approx(expected).epsilon(1e-9));
    CHECK(result.rgb[0] == Approx(expected).epsilon(1e-9));
  }
  // Explicit Euler (alpha = sigma delta, clipped to 1) on the slab as one segment: opaque, 58% too much.
  const double euler_opacity = std::min(1.0, slab_sigma * 1e-6);
  CHECK(euler_opacity - expected > 0.36);
  // Point samples of the slab converge as the step shrinks below its width (the grid is offset so that the
  // slab's edges fall inside segments).
  double previous_error = 1;
  for (const double step : {3.1e-7, 7.3e-8, 1.7e-8, 4.1e-9}) {  // not dividing the slab width
    SegmentRay ray;
    for (double t = 0.5 - 2e-6 + 0.37 * step; t < 0.5 + 2e-6; t += step) {
      ray.sigma.push_back(t + 0.5 * step >= slab_begin && t + 0.5 * step < slab_end ? slab_sigma : 0.0);
      ray.rgb.insert(ray.rgb.end(), {1, 0, 0});
      ray.delta.push_back(step);
      ray.t.push_back(t + 0.5 * step);
    }
    const double error = std::abs(Composite(ray.segments(), kBlack, 0.0).opacity - expected);
    INFO("point-sampled step " << step << " error " << error);
    CHECK(error <= previous_error + 1e-12);
    previous_error = error;
  }
  CHECK(previous_error < 0.02);
}

TEST_CASE("early termination stops once the ray is opaque, and changes the colour by at most the threshold",
          "[render]") {
  const SegmentRay ray = UniformRay(1000, 10.0, 5.0, {0.3, 0.6, 0.9});
  const CompositeResult<double> full = Composite(ray.segments(), kWhite, 0.0);
  const CompositeResult<double> early = Composite(ray.segments(), kWhite, 1e-4);
  CHECK(early.used < 250);
  CHECK(full.used == 1000);
  for (int c = 0; c < 3; ++c) CHECK(std::abs(early.rgb[c] - full.rgb[c]) < 1e-4);
}

TEST_CASE("volume rendering gradients match finite differences", "[render][gradients]") {
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> uniform(0, 1);
  SegmentRay ray;
  for (int i = 0; i < 12; ++i) {
    ray.sigma.push_back(4 * uniform(random));
    for (int c = 0; c < 3; ++c) ray.rgb.push_back(uniform(random));
    ray.delta.push_back(0.05 + 0.1 * uniform(random));
    ray.t.push_back(i * 0.2 + 0.1);
  }
  const double background[3] = {0.3, 0.6, 0.1};
  const double d_rgb[3] = {0.7, -1.3, 0.4};
  const double d_opacity = 0.5, d_depth = -0.2;
  const auto loss = [&](const SegmentRay& r) {
    const CompositeResult<double> out = Composite(r.segments(), background, 0.0);
    return d_rgb[0] * out.rgb[0] + d_rgb[1] * out.rgb[1] + d_rgb[2] * out.rgb[2] + d_opacity * out.opacity +
           d_depth * out.depth;
  };
  const CompositeResult<double> forward = Composite(ray.segments(), background, 0.0);
  std::vector<double> d_sigma(12), d_segment_rgb(36);
  CompositeBackward(ray.segments(), background, forward, d_rgb, d_opacity, d_depth, d_sigma.data(),
                    d_segment_rgb.data());
  const double h = 1e-6;
  for (size_t i = 0; i < 12; ++i) {
    SegmentRay plus = ray, minus = ray;
    plus.sigma[i] += h;
    minus.sigma[i] -= h;
    CHECK(d_sigma[i] == Approx((loss(plus) - loss(minus)) / (2 * h)).margin(1e-8));
    for (int c = 0; c < 3; ++c) {
      SegmentRay up = ray, down = ray;
      up.rgb[3 * i + c] += h;
      down.rgb[3 * i + c] -= h;
      CHECK(d_segment_rgb[3 * i + c] == Approx((loss(up) - loss(down)) / (2 * h)).margin(1e-8));
    }
  }
}

}  // namespace p2n::testing
