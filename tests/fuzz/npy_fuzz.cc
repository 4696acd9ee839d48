// libFuzzer: NumPy .npy (in memory) and .npz (as a file).
#include "base/errors.h"
#include "formats/npy.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    p2n::ParseNpy(std::string(reinterpret_cast<const char*>(data), size), "fuzz");
  } catch (const p2n::UserError&) {
  }
  const auto path = p2n::fuzz::ScratchDir() / "input.npz";
  p2n::fuzz::WriteBytes(path, data, size);
  try {
    p2n::ReadNpz(path);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
