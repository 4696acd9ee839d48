// libFuzzer: a dataset's transforms.json (the importer's parsing and validation; no image exists).
#include "base/errors.h"
#include "formats/dataset_import.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto dir = p2n::fuzz::ScratchDir() / "dataset";
  std::filesystem::create_directories(dir);
  p2n::fuzz::WriteBytes(dir / "transforms.json", data, size);
  try {
    p2n::LoadDataset(dir);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
