// Adam: the textbook update, and the sparse variant's per-entry step counts.

#include <catch2/catch.hpp>

#include <cmath>

#include "nerf/adam.h"

namespace p2n::testing {

TEST_CASE("the first Adam step moves each parameter by the learning rate against its gradient", "[adam]") {
  Adam<double> adam({0.1, 0.9, 0.999, 1e-12}, 3);
  std::vector<double> params = {1, 2, 3}, grads = {0.5, -2, 1e-3};
  adam.Step(params.data(), grads.data());
  CHECK(params[0] == Approx(0.9));
  CHECK(params[1] == Approx(2.1));
  CHECK(params[2] == Approx(2.9));
}

TEST_CASE("Adam minimises a quadratic", "[adam]") {
  Adam<double> adam({0.05, 0.9, 0.999, 1e-8}, 2);
  std::vector<double> x = {3, -4};
  for (int step = 0; step < 2000; ++step) {
    std::vector<double> grads = {2 * (x[0] - 1), 8 * (x[1] + 2)};
    adam.Step(x.data(), grads.data());
  }
  CHECK(x[0] == Approx(1).margin(1e-3));
  CHECK(x[1] == Approx(-2).margin(1e-3));
}

TEST_CASE("sparse Adam equals dense Adam when every entry is touched, and counts steps per entry", "[adam]") {
  Adam<double> dense({0.01, 0.9, 0.99, 1e-15}, 4, 2), sparse({0.01, 0.9, 0.99, 1e-15}, 4, 2);
  std::vector<double> a = {1, 2, 3, 4}, b = a;
  for (int step = 0; step < 5; ++step) {
    const std::vector<double> grads = {0.1 * step, -0.2, 0.3, 0.05 * step};
    std::vector<double> consumed = grads;
    dense.Step(a.data(), grads.data());
    sparse.StepSparse(b.data(), consumed.data());
    CHECK(consumed == std::vector<double>(4, 0.0));  // the sparse step zeroes the gradient it used
  }
  for (int k = 0; k < 4; ++k) CHECK(a[k] == Approx(b[k]));
  // An entry whose gradient is zero takes no step; one first touched at a later step gets the full first-step
  // update (bias correction of step 1), not one shrunk by the steps it took no part in.
  Adam<double> late({0.01, 0.9, 0.99, 1e-15}, 4, 2);
  std::vector<double> params = {0, 0, 0, 0};
  for (int step = 0; step < 10; ++step) {
    std::vector<double> grads = {1, 1, 0, 0};
    late.StepSparse(params.data(), grads.data());
  }
  CHECK(params[2] == 0);
  CHECK(params[3] == 0);
  std::vector<double> grads = {0, 0, 1, 1};
  late.StepSparse(params.data(), grads.data());
  CHECK(params[2] == Approx(-0.01));
  CHECK(params[3] == Approx(-0.01));
  // The same with entries of three values (the general path; the hash grid's two values have their own), one value
  // of the late entry touched: the whole entry takes the step, its untouched values keep zero moments.
  Adam<double> late3({0.01, 0.9, 0.99, 1e-15}, 6, 3);
  std::vector<double> params3(6, 0.0);
  for (int step = 0; step < 10; ++step) {
    std::vector<double> grads3 = {1, 1, 1, 0, 0, 0};
    late3.StepSparse(params3.data(), grads3.data());
  }
  CHECK(params3 == std::vector<double>{params3[0], params3[0], params3[0], 0, 0, 0});
  std::vector<double> grads3 = {0, 0, 0, 0, 1, 0};
  late3.StepSparse(params3.data(), grads3.data());
  CHECK(params3[3] == 0);
  CHECK(params3[4] == Approx(-0.01));
  CHECK(params3[5] == 0);
}

TEST_CASE("sparse Adam over float entries of two values (the hash grid's, vectorised) follows each entry's own steps",
          "[adam]") {
  // 43 entries: ten whole registers of four and three more. Each step leaves some entries untouched and gives
  // others a gradient in one value only; the reference follows Adam's rule in double, entry by entry.
  const size_t entries = 43;
  const double rate = 0.01, beta1 = 0.9, beta2 = 0.99, epsilon = 1e-15;
  Adam<float> adam({rate, beta1, beta2, epsilon}, 2 * entries, 2);
  std::vector<float> params(2 * entries);
  std::vector<double> expected(2 * entries), m(2 * entries, 0.0), v(2 * entries, 0.0);
  for (size_t k = 0; k < params.size(); ++k) expected[k] = params[k] = 0.01f * static_cast<float>(k);
  std::vector<int> steps(entries, 0);
  for (int step = 0; step < 6; ++step) {
    std::vector<float> grads(2 * entries, 0.0f);
    for (size_t e = 0; e < entries; ++e) {
      const size_t kind = (e * 7 + step * 3) % 4;  // 0: untouched, 1: first value only, 2: second only, 3: both
      if (kind & 1) grads[2 * e] = 0.3f * std::sin(float(e + step));
      if (kind & 2) grads[2 * e + 1] = -0.2f * std::cos(float(e * step));
    }
    for (size_t e = 0; e < entries; ++e) {
      if (grads[2 * e] == 0 && grads[2 * e + 1] == 0) continue;
      const int t = ++steps[e];
      for (size_t k = 2 * e; k < 2 * e + 2; ++k) {
        m[k] = beta1 * m[k] + (1 - beta1) * grads[k];
        v[k] = beta2 * v[k] + (1 - beta2) * grads[k] * grads[k];
        expected[k] -= rate / (1 - std::pow(beta1, t)) * m[k] / (std::sqrt(v[k] / (1 - std::pow(beta2, t))) + epsilon);
      }
    }
    adam.StepSparse(params.data(), grads.data());
    CHECK(grads == std::vector<float>(2 * entries, 0.0f));
    for (size_t k = 0; k < params.size(); ++k) {
      CAPTURE(step, k);
      CHECK(params[k] == Approx(expected[k]).margin(1e-6));
      if (steps[k / 2] == 0) CHECK(params[k] == static_cast<float>(expected[k]));  // never touched: as it was
    }
  }
}

TEST_CASE("sparse Adam given touch marks reads only the marked groups, updates them as without marks and clears them",
          "[adam]") {
  const size_t entries = 40, group = TouchMarks::kGroupEntries;
  Adam<double> with_marks({0.01, 0.9, 0.99, 1e-15}, 2 * entries, 2), without({0.01, 0.9, 0.99, 1e-15}, 2 * entries, 2);
  std::vector<double> a(2 * entries, 1.0), b = a;
  TouchMarks marks(entries);
  for (int step = 0; step < 3; ++step) {
    std::vector<double> grads(2 * entries, 0.0);
    for (const size_t entry : {size_t{3}, size_t{17}, size_t{39}}) {
      grads[2 * entry] = 0.1 * (step + 1);
      marks.Mark(entry);
    }
    std::vector<double> unmarked = grads;
    with_marks.StepSparse(a.data(), grads.data(), &marks);
    without.StepSparse(b.data(), unmarked.data());
    CHECK(a == b);
    CHECK(grads == std::vector<double>(2 * entries, 0.0));
    for (size_t g = 0; g < marks.groups(); ++g) CHECK_FALSE(marks.marked(g));
  }
  // A gradient in a group nobody marked is not read: the marks are a promise.
  std::vector<double> grads(2 * entries, 0.0);
  grads[2 * 25] = 1;
  with_marks.StepSparse(a.data(), grads.data(), &marks);
  CHECK(a[2 * 25] == 1.0);
  CHECK(grads[2 * 25] == 1.0);
  CHECK(25 / group != 17 / group);
}

TEST_CASE("Adam::Remap carries each kept entry's moments and starts new entries from zero", "[adam]") {
  // Two entries of two values; after one step, entry 1 is kept twice (cloned), entry 0 dropped, one added.
  Adam<double> adam(AdamOptions{}, 4, 2);
  std::vector<double> params = {0, 0, 0, 0};
  const std::vector<double> grads = {1, 1, 2, -3};
  adam.Step(params.data(), grads.data());
  adam.Remap({1, 1, -1});
  // A second step with zero gradients: the kept entries move by their carried first moment; the new one not at all.
  std::vector<double> after = {0, 0, 0, 0, 0, 0}, none(6, 0.0);
  adam.Step(after.data(), none.data());
  CHECK(after[0] < 0);
  CHECK(after[1] > 0);  // entry 1's second value had gradient -3
  CHECK(after[2] == after[0]);
  CHECK(after[3] == after[1]);
  CHECK(after[4] == 0);
  CHECK(after[5] == 0);
  CHECK_THROWS_AS(adam.Remap({5}), std::out_of_range);
}

}  // namespace p2n::testing
