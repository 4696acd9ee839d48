// libFuzzer: image files as ingest and training read them (OpenImageIO's decoders behind ReadImage), then the
// steps ingest takes with a decoded image. The first byte picks the file extension, which picks the decoder
// OpenImageIO tries first.
#include <array>

#include "base/image_io.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static constexpr std::array<const char*, 4> kExtensions = {"png", "jpg", "tif", "exr"};
  const auto path = p2n::fuzz::ScratchDir() / (std::string("input.") + kExtensions[data[0] % kExtensions.size()]);
  p2n::fuzz::WriteBytes(path, data + 1, size - 1);
  const p2n::ReadImageResult read = p2n::ReadImage(path);
  if (!read.ok()) return 0;
  p2n::PixelFingerprint(read.image);
  p2n::DownsizeToFit(read.image, 16);
  return 0;
}
