// libFuzzer: model.bin (the trained model a user may be sent), read from memory.
#include <stdexcept>

#include "nerf/nerf_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  p2n::BinaryReader reader(std::vector<char>(data, data + size), "fuzz");
  try {
    p2n::ReadModel(&reader);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
