// libFuzzer: a poses stage's sparse_tracks.json (the train stage's depth points read it).
#include "base/errors.h"
#include "formats/sparse_tracks.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / "sparse_tracks.json";
  p2n::fuzz::WriteBytes(file, data, size);
  try {
    p2n::SparseTracks::Read(file);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
