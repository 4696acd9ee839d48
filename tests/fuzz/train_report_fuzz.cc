// libFuzzer: train_report.json's camera refinement, as the export stage reads it back.
#include "pipeline/errors.h"
#include "stages/camera_corrections.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / "train_report.json";
  p2n::fuzz::WriteBytes(file, data, size);
  try {
    p2n::ReadCameraCorrections(file);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
