#pragma once
// The pages' scripts, bundled at build time (CMakeLists.txt): the splat viewer's (three.js, Spark and src/viewer.js)
// and the report's mesh view (three.js and src/mesh_viewer.js).

#include <string_view>

namespace p2n {

std::string_view ViewerBundle();
std::string_view MeshViewerBundle();

}  // namespace p2n
