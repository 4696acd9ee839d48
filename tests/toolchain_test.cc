// The compiler and flags this build uses get simple code right (CMakeLists.txt: GCC 12 with AVX-512
// miscompiled constant initialisation, which made the sparse Adam test fail for a reason outside our code).

#include <catch2/catch.hpp>

#include <vector>

namespace p2n::testing {
namespace {

// Not inlined: the values must be stored to memory and read back, as they are where the bug showed.
__attribute__((noinline)) std::vector<double> FourDoubles() { return {1, 1, 0, 0}; }
__attribute__((noinline)) std::vector<float> EightFloats() { return {1, 1, 1, 1, 0, 0, 0, 0}; }

TEST_CASE("the compiler initialises constant vectors as written (GCC 12 with AVX-512 did not)", "[toolchain]") {
  CHECK(FourDoubles() == std::vector<double>{1, 1, 0, 0});
  const std::vector<double> again = FourDoubles();
  CHECK(again[2] == 0);
  CHECK(again[3] == 0);
  const std::vector<float> floats = EightFloats();
  for (int k = 0; k < 8; ++k) CHECK(floats[k] == (k < 4 ? 1.0f : 0.0f));
}

}  // namespace
}  // namespace p2n::testing
