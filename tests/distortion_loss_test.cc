// The distortion loss (issue 16): its linear-time form against the pairwise definition, analytic cases, and its
// gradient against finite differences in double precision.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "nerf/distortion_loss.h"
#include "tests/segment_ray.h"

namespace p2n::testing {
namespace {

// Segments of random lengths (some gaps between them, as empty space leaps leave) and random densities.
SegmentRay RandomRay(size_t n, std::mt19937_64* random) {
  std::uniform_real_distribution<double> length(0.01, 0.2), gap(0.0, 0.3), density(0.0, 8.0);
  SegmentRay ray;
  double start = 0.1;
  for (size_t i = 0; i < n; ++i) {
    start += (i % 3 == 0) ? gap(*random) : 0.0;
    ray.delta.push_back(length(*random));
    ray.t.push_back(start + 0.5 * ray.delta.back());
    ray.sigma.push_back(i % 5 == 4 ? 0.0 : density(*random));
    ray.rgb.insert(ray.rgb.end(), {0.5, 0.5, 0.5});
    start += ray.delta.back();
  }
  return ray;
}

// The definition, O(n^2).
double Pairwise(const SegmentRay& ray) {
  std::vector<double> w;
  double log_t = 0;
  for (size_t i = 0; i < ray.sigma.size(); ++i) {
    w.push_back(std::exp(log_t) * -std::expm1(-ray.sigma[i] * ray.delta[i]));
    log_t -= ray.sigma[i] * ray.delta[i];
  }
  double loss = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    for (size_t j = 0; j < w.size(); ++j) loss += w[i] * w[j] * std::abs(ray.t[i] - ray.t[j]);
    loss += w[i] * w[i] * ray.delta[i] / 3;
  }
  return loss;
}

// The loss of the first `count` segments (all by default), midpoints and lengths in world units.
double Loss(const SegmentRay& ray, size_t count = SIZE_MAX) {
  return DistortionLoss(ray.segments(), count, ray.t.data(), ray.delta.data(), 1.0, static_cast<double*>(nullptr));
}

}  // namespace

TEST_CASE("the distortion loss's linear-time form equals its pairwise definition", "[render][distortion]") {
  std::mt19937_64 random(7);
  for (const size_t n : {1u, 2u, 5u, 40u}) {
    const SegmentRay ray = RandomRay(n, &random);
    CHECK(Loss(ray) == Approx(Pairwise(ray)).epsilon(1e-12).margin(1e-15));
  }
}

TEST_CASE("the distortion loss: analytic cases", "[render][distortion]") {
  // One opaque segment of length l: w = 1, L = l / 3.
  SegmentRay one{{1e6}, {0, 0, 0}, {0.5}, {0.3}};
  CHECK(Loss(one) == Approx(0.1).epsilon(1e-9));
  // Two thin segments 2 apart with alpha 1/2 and 3/4, so weights 1/2 and 3/8: L = 2 w1 w2 2 + (w1^2 + w2^2) l / 3.
  const double half = std::log(2.0) / 1e-3;  // sigma with 1 - exp(-sigma * 1e-3) = 1/2
  SegmentRay two{{half, 2 * half}, {0, 0, 0, 0, 0, 0}, {1.0, 3.0}, {1e-3, 1e-3}};
  CHECK(Loss(two) == Approx(0.75 + (0.25 + 0.140625) * 1e-3 / 3).epsilon(1e-9));
  // Empty space costs nothing; haze spread over the ray costs more than the same opacity in one place.
  SegmentRay empty{{0, 0}, {0, 0, 0, 0, 0, 0}, {1, 2}, {1, 1}};
  CHECK(Loss(empty) == 0.0);
  SegmentRay haze, surface;
  for (int i = 0; i < 50; ++i) {
    haze.sigma.push_back(1.0);  // the same optical depth (5) as the surface, spread over the ray
    surface.sigma.push_back(i == 25 ? 50.0 : 0.0);
    for (SegmentRay* ray : {&haze, &surface}) {
      ray->t.push_back(0.1 * i + 0.05);
      ray->delta.push_back(0.1);
      ray->rgb.insert(ray->rgb.end(), {0, 0, 0});
    }
  }
  CHECK(Loss(surface) < 0.1 * Loss(haze));
  // Only the first `count` segments count (early termination).
  CHECK(Loss(haze, 0) == 0.0);
  CHECK(Loss(haze, 10) < Loss(haze));
}

TEST_CASE("the distortion loss's gradient matches finite differences", "[render][distortion][gradients]") {
  std::mt19937_64 random(11);
  const SegmentRay ray = RandomRay(30, &random);
  std::vector<double> d_sigma(ray.sigma.size(), 0.25);  // added to, not overwritten
  const double scale = 0.7;
  DistortionLoss(ray.segments(), ray.sigma.size(), ray.t.data(), ray.delta.data(), scale, d_sigma.data());
  for (size_t i = 0; i < ray.sigma.size(); ++i) {
    if (ray.sigma[i] == 0) {
      CHECK(d_sigma[i] == 0.25);  // no gradient where the density is clamped at zero
      continue;
    }
    const double h = 1e-6 * std::max(1.0, ray.sigma[i]);
    SegmentRay plus = ray, minus = ray;
    plus.sigma[i] += h;
    minus.sigma[i] -= h;
    const double numeric = scale * (Loss(plus) - Loss(minus)) / (2 * h);
    CHECK(d_sigma[i] - 0.25 == Approx(numeric).epsilon(1e-6).margin(1e-9));
  }
}

TEST_CASE("the distortion loss is finite for extreme densities and lengths", "[render][distortion]") {
  for (const double sigma : {0.0, 1e-30, 1e8, 1e30, std::nan("")}) {
    for (const double delta : {0.0, 1e-9, 1e3}) {
      SegmentRay ray{{sigma, sigma, sigma}, std::vector<double>(9, 0.5), {1, 2, 3}, {delta, delta, delta}};
      std::vector<double> d_sigma(3, 0.0);
      const double loss = DistortionLoss(ray.segments(), 3, ray.t.data(), ray.delta.data(), 1.0, d_sigma.data());
      CHECK(std::isfinite(loss));
      for (const double d : d_sigma) CHECK(std::isfinite(d));
    }
  }
}

}  // namespace p2n::testing
