// Per-image colour transforms: the forward map and its gradient against finite differences, the closed-form fit
// recovering a known transform, and the identity where a fit is ill-posed.

#include <catch2/catch.hpp>

#include <random>

#include "nerf/appearance.h"

namespace p2n::testing {
namespace {

// A transform with every parameter away from the identity's.
std::vector<float> SomeTransform() {
  return {0.9f, 0.05f, -0.02f, 0.03f, 1.1f, 0.04f, -0.01f, 0.02f, 0.8f, 0.05f, -0.03f, 0.1f};
}

TEST_CASE("appearance: the identity keeps colours, and a transform maps them affinely", "[appearance]") {
  const std::vector<float> identity = IdentityAppearance(2);
  REQUIRE(identity.size() == 2 * kAppearanceParams);
  const float in[3] = {0.2f, 0.5f, 0.9f};
  float out[3];
  ApplyAppearance(&identity[kAppearanceParams], in, out);
  CHECK(out[0] == in[0]);
  CHECK(out[1] == in[1]);
  CHECK(out[2] == in[2]);
  CHECK(AppearanceGain(identity.data()) == 1.0);
  const std::vector<float> t = SomeTransform();
  ApplyAppearance(t.data(), in, out);
  CHECK(out[1] == Approx(0.03 * 0.2 + 1.1 * 0.5 + 0.04 * 0.9 - 0.03));
  CHECK(AppearanceGain(t.data()) == Approx((0.93 + 1.17 + 0.81 + 0.12) / 3).epsilon(1e-5));
}

TEST_CASE("appearance: centring makes the mean transform the identity and keeps their differences", "[appearance]") {
  std::vector<float> params = IdentityAppearance(3);
  const std::vector<float> t = SomeTransform();
  std::copy(t.begin(), t.end(), params.begin());
  params[kAppearanceParams + 9] = 0.3f;  // the second view's red offset
  const std::vector<float> before = params;
  CentreAppearance(&params);
  const std::vector<float> identity = IdentityAppearance(1);
  for (int k = 0; k < kAppearanceParams; ++k) {
    INFO("parameter " << k);
    CHECK((params[k] + params[kAppearanceParams + k] + params[2 * kAppearanceParams + k]) / 3 ==
          Approx(identity[k]).margin(1e-6));
    CHECK(params[k] - params[2 * kAppearanceParams + k] == Approx(before[k] - before[2 * kAppearanceParams + k]));
  }
}

TEST_CASE("appearance: the gradient matches finite differences", "[appearance]") {
  std::vector<float> t = SomeTransform();
  const float in[3] = {0.3f, 0.6f, 0.1f}, d_out[3] = {0.7f, -0.4f, 0.2f};
  std::vector<float> grads(kAppearanceParams, 0.0f);
  float d_in[3];
  AppearanceBackward(t.data(), in, d_out, grads.data(), d_in);
  // L = d_out . out is linear: the finite differences are exact up to rounding.
  const auto loss = [&](const std::vector<float>& params, const float* x) {
    float out[3];
    ApplyAppearance(params.data(), x, out);
    return double(d_out[0]) * out[0] + double(d_out[1]) * out[1] + double(d_out[2]) * out[2];
  };
  const double h = 1e-2;
  for (int k = 0; k < kAppearanceParams; ++k) {
    std::vector<float> up = t, down = t;
    up[k] += static_cast<float>(h);
    down[k] -= static_cast<float>(h);
    INFO("parameter " << k);
    CHECK(grads[k] == Approx((loss(up, in) - loss(down, in)) / (2 * h)).margin(1e-4));
  }
  for (int c = 0; c < 3; ++c) {
    float up[3] = {in[0], in[1], in[2]}, down[3] = {in[0], in[1], in[2]};
    up[c] += static_cast<float>(h);
    down[c] -= static_cast<float>(h);
    CHECK(d_in[c] == Approx((loss(t, up) - loss(t, down)) / (2 * h)).margin(1e-4));
  }
}

TEST_CASE("appearance: the least-squares fit recovers a known transform, and ill-posed fits keep the identity",
          "[appearance]") {
  const std::vector<float> truth = SomeTransform();
  std::mt19937 random(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> rendered, target;
  for (int i = 0; i < 500; ++i) {
    const float in[3] = {unit(random), unit(random), unit(random)};
    float out[3];
    ApplyAppearance(truth.data(), in, out);
    rendered.insert(rendered.end(), in, in + 3);
    target.insert(target.end(), out, out + 3);
  }
  const std::vector<float> fitted = FitAppearance(rendered.data(), target.data(), 500);
  for (int k = 0; k < kAppearanceParams; ++k) CHECK(fitted[k] == Approx(truth[k]).margin(1e-4));
  // No pixels, or grey pixels only (every colour on one line) that the identity fits: the identity.
  const std::vector<float> identity = IdentityAppearance(1);
  std::vector<float> grey;
  for (int i = 0; i < 100; ++i) grey.insert(grey.end(), 3, i / 100.0f);
  const std::vector<float> none = FitAppearance(nullptr, nullptr, 0);
  const std::vector<float> from_grey = FitAppearance(grey.data(), grey.data(), 100);
  for (int k = 0; k < kAppearanceParams; ++k) {
    CHECK(none[k] == Approx(identity[k]).margin(1e-6));
    CHECK(from_grey[k] == Approx(identity[k]).margin(1e-4));
  }
}

}  // namespace
}  // namespace p2n::testing
