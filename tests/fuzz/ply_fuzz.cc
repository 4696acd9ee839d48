// libFuzzer: the PLY reader, and the writer's round trip of what it read.
#include <cstdlib>

#include "base/errors.h"
#include "formats/ply.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = p2n::fuzz::ScratchDir() / "input.ply";
  p2n::fuzz::WriteBytes(path, data, size);
  std::vector<p2n::ColouredPoint> points;
  try {
    points = p2n::ReadPly(path);
  } catch (const p2n::UserError&) {
    return 0;
  }
  const auto copy = p2n::fuzz::ScratchDir() / "copy.ply";
  p2n::WritePly(copy, points);
  const auto again = p2n::ReadPly(copy);
  if (again.size() != points.size()) std::abort();
  return 0;
}
