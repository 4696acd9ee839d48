// libFuzzer: the KHR_gaussian_splatting glTF reader (tinygltf's parsing, then our accessors' bounds), and the
// writer's round trip of what it read.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "splat/splat_gltf.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  p2n::Gaussians<float> gaussians;
  try {
    gaussians = p2n::ParseSplatGlb(bytes, "input.glb");
  } catch (const std::runtime_error&) {
    return 0;
  }
  const p2n::Gaussians<float> again = p2n::ParseSplatGlb(p2n::SplatGlbBytes(gaussians, "fuzz"), "copy.glb");
  if (again.size() != gaussians.size() || again.sh_degree != gaussians.sh_degree) std::abort();
  return 0;
}
