// libFuzzer: COLMAP models, binary and text: the input is split into cameras, images and points3D.
#include <fstream>

#include "base/errors.h"
#include "formats/colmap_model.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto pieces = p2n::fuzz::Split(data, size, 3);
  const auto dir = p2n::fuzz::ScratchDir();
  const char* binary[] = {"cameras.bin", "images.bin", "points3D.bin"};
  const char* text[] = {"cameras.txt", "images.txt", "points3D.txt"};
  for (int i = 0; i < 3; ++i) {
    std::ofstream(dir / binary[i], std::ios::binary | std::ios::trunc) << pieces[i];
    std::ofstream(dir / text[i], std::ios::binary | std::ios::trunc) << pieces[i];
  }
  try {
    p2n::ReadColmapModelBinary(dir);
  } catch (const p2n::UserError&) {
  }
  try {
    p2n::ReadColmapModelText(dir);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
