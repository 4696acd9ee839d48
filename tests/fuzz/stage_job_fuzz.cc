// libFuzzer: a Slurm job's job.json, as `photo2nerf stage-job` reads it on a node.
#include "base/errors.h"
#include "pipeline/slurm.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = p2n::fuzz::ScratchDir() / "job.json";
  p2n::fuzz::WriteBytes(file, data, size);
  try {
    p2n::ReadStageJob(file);
  } catch (const p2n::UserError&) {
  }
  return 0;
}
