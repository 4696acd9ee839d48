// libFuzzer: COLMAP's database (an SQLite file) as the sfm stage reads it: the images, each image's descriptors
// and a pair's matches.
#include "base/errors.h"
#include "formats/colmap_database.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = p2n::fuzz::ScratchDir() / "database.db";
  p2n::fuzz::WriteBytes(path, data, size);
  try {
    p2n::ColmapDatabase db(path);
    for (const p2n::ColmapDatabaseImage& image : db.Images()) db.Descriptors(image.id);
    db.HasMatches(1, 2);
  } catch (const p2n::ExternalToolError&) {
  }
  return 0;
}
