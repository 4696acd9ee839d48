// libFuzzer: a stage's manifest.json, as the runner reads it to tell whether the stage is fresh.
#include "base/errors.h"
#include "base/file_util.h"
#include "pipeline/manifest.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / p2n::kManifestName;
  p2n::fuzz::WriteBytes(file, data, size);
  try {
    const p2n::Manifest manifest = p2n::Manifest::FromJson(p2n::ReadJsonFile(file), file.string());
    p2n::OutputsDigest(manifest.outputs);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
