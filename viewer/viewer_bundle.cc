#include "viewer/viewer_bundle.h"

#include <cstddef>

// The bundles' bytes, included by the assembler from the build folder (P2N_VIEWER_BUNDLE, P2N_MESH_VIEWER_BUNDLE),
// each between two symbols.
asm(R"(
  .section .rodata
  .global p2n_viewer_bundle_begin
p2n_viewer_bundle_begin:
  .incbin ")" P2N_VIEWER_BUNDLE R"("
  .global p2n_viewer_bundle_end
p2n_viewer_bundle_end:
  .byte 0
  .global p2n_mesh_viewer_bundle_begin
p2n_mesh_viewer_bundle_begin:
  .incbin ")" P2N_MESH_VIEWER_BUNDLE R"("
  .global p2n_mesh_viewer_bundle_end
p2n_mesh_viewer_bundle_end:
  .byte 0
  .previous
)");

extern "C" const char p2n_viewer_bundle_begin[];
extern "C" const char p2n_viewer_bundle_end[];
extern "C" const char p2n_mesh_viewer_bundle_begin[];
extern "C" const char p2n_mesh_viewer_bundle_end[];

namespace p2n {

std::string_view ViewerBundle() {
  return {p2n_viewer_bundle_begin, static_cast<size_t>(p2n_viewer_bundle_end - p2n_viewer_bundle_begin)};
}

std::string_view MeshViewerBundle() {
  return {p2n_mesh_viewer_bundle_begin, static_cast<size_t>(p2n_mesh_viewer_bundle_end - p2n_mesh_viewer_bundle_begin)};
}

}  // namespace p2n
