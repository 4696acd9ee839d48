// libFuzzer: the SPZ reader (its gzip stream, header and body), and the writer's round trip of what it read.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "splat/spz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  p2n::Gaussians<float> gaussians;
  try {
    gaussians = p2n::ParseSpz(bytes, "input.spz");
  } catch (const std::runtime_error&) {
    return 0;
  }
  const std::vector<char> written = p2n::SpzBytes(gaussians);
  const p2n::Gaussians<float> again = p2n::ParseSpz(std::string(written.begin(), written.end()), "copy.spz");
  if (again.size() != gaussians.size() || again.sh_degree != gaussians.sh_degree) std::abort();
  return 0;
}
