#pragma once
// The viewer page's script: three.js, Spark and src/viewer.js, bundled at build time (CMakeLists.txt).

#include <string_view>

namespace p2n {

std::string_view ViewerBundle();

}  // namespace p2n
